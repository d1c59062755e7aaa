"""The identified model in MuJoCo: `excite identify --mjcf-out` on the real Panda run of ../shared/data
(blocks split) and on the shipped simulated runs. For each it prints MuJoCo's check of the written
MJCF (rigid body, armature and damping against excite's model, relative to the largest torque;
Coulomb friction where both are saturated; the share of samples where the two friction models
differ by more than 1 % of F_c), the mean validation errors of excite's consistent model, of its
part the MJCF holds and of MuJoCo's, then the same MuJoCo error with MuJoCo's default friction
constraint (solreffriction 0.02 s instead of 2 timesteps), and the time. the figures of the documentation under
"The identified model in MuJoCo".

    .venv/bin/python bench/mjcf_panda.py
"""

from __future__ import annotations

import re
import tempfile
import time
from pathlib import Path

from excite_cli.config_file import load_problem
from excite_cli.identification.config import IdentifyProblem
from excite_cli.identification.reporting.mjcf_check import check_mjcf
from excite_cli.workflows.identify import run_identify

ROOT = Path(__file__).resolve().parent.parent
CONFIGS = {"real Panda (blocks)": "panda_identify.yaml", "simulated (shipped)": "panda_identify_simulated.yaml"}


def main() -> None:
    print(
        f"{'data':<22}{'rigid':>9}{'friction':>10}{'differs':>9}{'excite':>8}{'MJCF part':>10}"
        f"{'MuJoCo':>8}{'default':>9}{'time':>7}"
    )
    with tempfile.TemporaryDirectory() as tmp:
        for label, name in CONFIGS.items():
            problem = load_problem(ROOT / "configs" / name, IdentifyProblem)
            start = time.perf_counter()
            run = run_identify(problem, Path(tmp) / f"{name}.h5", force=True, mjcf_out=Path(tmp) / f"{name}.xml")
            took = time.perf_counter() - start
            check, model = run.mujoco, run.mjcf
            text = model.path.read_text()
            model.path.write_text(re.sub(r' solreffriction="[^"]*"', "", text))  # MuJoCo's default, 0.02 s
            default = check_mjcf(problem, run.report, run.robot, run.base, model)
            print(
                f"{label:<22}{check.rigid:>9.1e}{check.friction:>10.1e}{check.friction_differs:>8.1f}%"
                f"{check.relative_excite.mean():>7.2f}%{check.relative_written.mean():>9.2f}%"
                f"{check.relative_mujoco.mean():>7.2f}%{default.relative_mujoco.mean():>8.2f}%{took:>6.0f}s"
            )
            for term, coefficient, value, why in model.unwritten:
                share = dict(check.unwritten)[term.label(run.report.joints)]
                print(
                    f"    not in the MJCF: {term.label(run.report.joints)} {coefficient} = {value:.3g} ({share:+.2f} points)"
                )


if __name__ == "__main__":
    main()
