"""The whole loop on physics nobody here wrote, from the commands a user types: `excite optimize
configs/panda.yaml` (3 iterations), `excite rehearse --mjcf` on MuJoCo Menagerie's Panda MJCF
(../shared/data/menagerie: its own inertias, joint damping and armature, the meshes left out) with
`--record` and, for the noisy rows, `--effects` giving the recording's torque and position noise, then
`excite identify` on example-robot-data's URDF with nothing declared (iterations 1 and 2 fitted, 3
validating).

Printed per noise: what identify found against the MJCF's joint fields (damping, armature, frictionloss),
the validation error per joint [%], and MuJoCo's own floor: the Menagerie model's inverse dynamics
(``mj_inverse``) on the validation run's samples through excite's preprocessing (the check of
``identify --mjcf-out``, excite_cli/identification/reporting/mjcf_check.py, run on Menagerie's file:
the true model, nothing fitted), with the ratio of the two means.

    .venv/bin/python bench/rehearse_loop.py [--result panda.h5] [--noise 0 0.05 ...]

--result: an optimize result of configs/panda.yaml to rehearse (default: optimized here, ~1 min);
--noise: torque noise [N·m] per row (each with an 18-bit encoder's position noise, none for 0).
Asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import mujoco
import numpy as np
import yaml

from excite_cli.config_file import load_problem
from excite_cli.dynamics.mjcf_compiled import without_meshes
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.reporting.mjcf_check import check_mjcf
from excite_cli.identification.reporting.mjcf_out import MjcfModel
from excite_cli.workflows.identify import run_identify

ROOT = Path(__file__).resolve().parent.parent
MENAGERIE = ROOT.parent / "shared" / "data" / "menagerie" / "franka_emika_panda" / "panda.xml"
JOINTS = [f"panda_joint{k}" for k in range(1, 8)]
#: An 18-bit encoder's quantization as noise [rad]: 2π / 2¹⁸ / √12.
ENCODER = 2 * np.pi / 2**18 / np.sqrt(12)
EXCITE = [str(Path(sys.executable).parent / "excite")]


def renamed(folder: Path) -> Path:
    """Menagerie's Panda without its meshes (their bodies' inertias are explicit), its arm joints named as
    the URDF's (what ``--joint-names`` maps) for the floor's MuJoCo replay, which finds the joints by the
    identified model's names; its actuators and keyframes left out (inverse dynamics gives the joint torques)."""
    spec = without_meshes(mujoco, str(MENAGERIE))
    for element in [*spec.actuators, *spec.keys]:  # a keyframe holds the actuators' controls
        spec.delete(element)
    for joint in spec.joints:
        if joint.name in [f"joint{k}" for k in range(1, 8)]:
            joint.name = f"panda_{joint.name}"
    spec.compile()
    path = folder / "panda_urdf_names.xml"
    path.write_text(spec.to_xml())
    return path


def loop(folder: Path, result: Path, noise: float) -> None:
    """Rehearse, record, identify and print one row (module docstring)."""
    runs = folder / f"runs_{noise:g}"
    extra = []
    if noise > 0:
        effects = folder / f"noise_{noise:g}.yaml"
        effects.write_text(yaml.safe_dump({"torque_noise": noise, "position_noise": float(ENCODER), "seed": 1}))
        extra = ["--effects", str(effects)]
    names = ",".join(f"{j}=joint{k}" for k, j in enumerate(JOINTS, 1))
    played = subprocess.run(
        [*EXCITE, "rehearse", str(result), "--mjcf", str(MENAGERIE), "--joint-names", names, "--record", str(runs)]
        + ["--plot", str(folder / f"rehearsal_{noise:g}.png"), "--force", *extra],
        capture_output=True,
        text=True,
    )
    print(f"rehearse (noise {noise:g} N·m): exit {played.returncode}; {played.stdout.strip().splitlines()[-1]}")
    config = {
        "robot": {"urdf": "panda_description/urdf/panda.urdf", "source": "example-robot-data", "active_joints": JOINTS},
        "data": {
            "runs": [
                {"file": str(runs / f"rehearsal_{k}.csv"), "role": role}
                for k, role in zip((1, 2, 3), ("fit", "fit", "validation"))
            ],
            "columns": {"q": [f"q_{j}" for j in JOINTS], "tau": [f"tau_{j}" for j in JOINTS]},
        },
    }
    (folder / "identify.yaml").write_text(yaml.safe_dump(config))
    problem = load_problem(folder / "identify.yaml", IdentifyProblem)
    run = run_identify(problem, folder / f"identified_{noise:g}.h5", force=True)
    report = run.report
    floor_file = renamed(folder)
    model = mujoco.MjModel.from_xml_path(str(floor_file))
    dofs = [model.joint(j).dofadr[0] for j in JOINTS]
    truth = {
        "viscous": model.dof_damping[dofs],
        "armature": model.dof_armature[dofs],
        "coulomb": model.dof_frictionloss[dofs],
    }
    found = {}
    for term, _, value, _ in report.effect_values():
        found.setdefault(term.effect, {})[term.joint] = value
    for effect, values in truth.items():
        got = found.pop(effect, {})
        print(
            f"  {effect}: MJCF {', '.join(f'{v:g}' for v in values)}; found "
            + (", ".join(f"j{j + 1} {v:.4g}" for j, v in sorted(got.items())) or "none")
        )
    for effect, got in found.items():
        print(f"  also kept: {effect} " + ", ".join(f"j{j + 1} {v:.3g}" for j, v in sorted(got.items())))
    floor = check_mjcf(problem, report, run.robot, run.base, MjcfModel(floor_file, JOINTS)).relative_mujoco
    error = report.relative_after
    print(
        f"  validation error per joint [%]: {', '.join(f'{e:.2f}' for e in error)} (mean {error.mean():.3f}); "
        f"MuJoCo's own floor {', '.join(f'{e:.2f}' for e in floor)} (mean {floor.mean():.3f}); "
        f"ratio {error.mean() / floor.mean():.2f}; rigid model alone mean {report.relative_before.mean():.1f}",
        flush=True,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--result", type=Path, help="an optimize result of configs/panda.yaml")
    parser.add_argument("--noise", type=float, nargs="+", default=[0.0, 0.05, 0.2], help="torque noise [N·m]")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        result = args.result
        if result is None:
            result = folder / "panda.h5"
            subprocess.run([*EXCITE, "optimize", str(ROOT / "configs" / "panda.yaml"), "-o", str(result)], check=True)
        for noise in args.noise:
            loop(folder, result.resolve(), noise)


if __name__ == "__main__":
    main()
