"""Does the standing robot stay on its feet? Each iteration of the shipped G1 problem, optimized for
every seed, played in MuJoCo on a floor (excite_cli/design/mujoco_stance.py: MuJoCo compiles the
URDF itself; the soles' contact spheres, the free root, MuJoCo's integrator and soft contacts), as
`excite export` plays it (home → one period → home, at 2 kHz, speed 1 and faster), the moving joints
driven by the feed-forward torque plus a PD on tracking, the joints the problem locks held

- welded (rigid, as excite's model holds them): what excite's zero-moment point predicts, and
- by a PD (--stiffness, --damping; 1000 Nm/rad and 40 Nm·s/rad: a stance with compliance of its own).

One line per stance, seed, iteration and speed:
`balance ROBOT seed K iteration I speed S [STANCE]: CoP margin M mm (predicted P mm, RMS gap G mm),
tilt T deg, stands|falls` — MuJoCo's smallest distance of the centre of pressure (from the contact
forces) inside the polygon of its contact points, excite's predicted smallest ZMP margin on the same
samples, the RMS distance between the two points, the largest tilt of a foot, and whether the root
dropped more than 5 cm. A summary line per stance and speed follows, then the PD stance's sway
frequencies: the root pushed (60 N for 50 ms) fore-aft and sideways while standing at home, the
peak of its centre of mass's free motion over 5.9 s.

    .venv/bin/python bench/balance.py [--config configs/g1_arms.yaml] [--seeds 0 1 2] [--result R.h5]

With --result the iterations of that result are played instead of optimizing. Asserts nothing.
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
import copy
import tempfile
from pathlib import Path

import numpy as np

from excite_cli.config_file import load_problem
from excite_cli.constraints.zmp import zero_moment_point
from excite_cli.design.mujoco_stance import TIMESTEP, Stance, play_standing, standing_model
from excite_cli.design.playback import plan_playback
from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.urdf_source import resolve_urdf
from excite_cli.identification.reporting.mjcf_out import import_mujoco
from excite_cli.storage.results import read_alphas
from excite_cli.workflows.optimize import run_optimize

ROOT = Path(__file__).resolve().parent.parent


def results(config: Path, seeds: list[int], given: Path | None, folder: Path) -> dict[int, dict[int, np.ndarray]]:
    """{seed: {iteration: α}}: of ``given``, or optimized for each seed."""
    if given is not None:
        return {load_problem(config).optimizer.seed: dict(read_alphas(given))}
    found = {}
    for seed in seeds:
        problem = load_problem(config)
        problem.optimizer.seed = seed
        target = folder / f"seed{seed}.h5"
        run_optimize(problem, target, force=True)
        found[seed] = dict(read_alphas(target))
        print(f"  optimized seed {seed}", flush=True)
    return found


def sway(model, joints: list[str], home: np.ndarray, locked: dict[str, float]) -> list[float]:
    """The frequencies [Hz] (fore-aft, sideways) at which the standing robot's centre of mass swings
    freely after a push of the root: 60 N for 50 ms after 2 s standing at ``home``."""
    mujoco = import_mujoco()
    settled = mujoco.MjData(model)
    play_standing(model, joints, locked, home[None], 0 * home[None], 0 * home[None], settled)
    found = []
    for axis in (0, 1):
        data = copy.copy(settled)
        track = []
        for k in range(12_000):
            data.xfrc_applied[1, axis] = 60.0 if k < 100 else 0.0
            mujoco.mj_step(model, data)
            track.append(data.subtree_com[1, axis])
        swing = np.array(track[200:]) - np.mean(track[200:])
        spectrum = np.abs(np.fft.rfft(swing))[1:]
        found.append(float(np.fft.rfftfreq(swing.size, TIMESTEP)[1:][np.argmax(spectrum)]))
    return found


def setup(config: Path):
    """The problem of ``config``, its excitation, its ZMP constraint, its URDF and locked joints."""
    problem = load_problem(config)
    excitation = build_excitation(problem)
    zmp = next(c for c in excitation.constraints if c.name == "zmp")
    return problem, excitation, zmp, resolve_urdf(problem.robot, problem.folder)[0], dict(problem.robot.locked_joints)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--config", type=Path, default=ROOT / "configs" / "g1_arms.yaml")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--speeds", type=float, nargs="+", default=[1.0, 1.25])
    parser.add_argument("--stiffness", type=float, default=1000.0, help="PD stance [Nm/rad]")
    parser.add_argument("--damping", type=float, default=40.0, help="PD stance [Nm·s/rad]")
    parser.add_argument("--result", type=Path, help="play this result's iterations instead of optimizing")
    args = parser.parse_args()
    problem, excitation, zmp, urdf, locked = setup(args.config)
    joints, robot = excitation.robot.joint_names, excitation.robot
    stances = [Stance(), Stance(args.stiffness, args.damping)]
    models = [standing_model(urdf, joints, locked, problem.constraints.zmp.support_links, s) for s in stances]
    with tempfile.TemporaryDirectory() as folder:
        alphas = results(args.config, args.seeds, args.result, Path(folder))
    summary: dict[tuple[str, float], list[tuple[float, float, bool]]] = {}
    for stance, model in zip(stances, models):
        for seed, iterations in alphas.items():
            for k, alpha in sorted(iterations.items()):
                playback = plan_playback(excitation, alpha)
                for speed in args.speeds:
                    _, q, qd, qdd = playback.sample(1.0 / TIMESTEP, speed=speed)
                    tau = np.array([robot.torques(*x) for x in zip(q, qd, qdd)])
                    run = play_standing(model, joints, locked, q, qd, tau)
                    predicted = zero_moment_point(zmp.wrenches(q, qd, qdd), zmp.polygon.height)
                    gap = np.sqrt(np.nanmean(np.sum((run.cop - predicted) ** 2, axis=1)))
                    margin, expected = run.margin.min(), zmp.polygon.margins(predicted).min()
                    summary.setdefault((str(stance), speed), []).append((margin, gap, run.fell))
                    print(
                        f"balance {args.config.stem} seed {seed} iteration {k} speed {speed:.2f} [{stance}]: "
                        f"CoP margin {1000 * margin:.1f} mm (predicted {1000 * expected:.1f} mm, RMS gap "
                        f"{1000 * gap:.1f} mm), tilt {run.tilt_deg.max():.2f} deg, {'falls' if run.fell else 'stands'}",
                        flush=True,
                    )
    fore_aft, sideways = sway(models[1], joints, excitation.home, locked)
    print(f"sway [{stances[1]}]: fore-aft {fore_aft:.2f} Hz, sideways {sideways:.2f} Hz")
    for (stance, speed), rows in summary.items():
        margins, gaps, fell = zip(*rows)
        print(
            f"summary [{stance}] speed {speed:.2f}: {len(rows) - sum(fell)} of {len(rows)} stand, smallest CoP "
            f"margin {1000 * min(margins):.1f} mm, largest RMS gap {1000 * max(gaps):.1f} mm"
        )


if __name__ == "__main__":
    main()
