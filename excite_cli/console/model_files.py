"""What ``identify`` prints about the model files it wrote: the URDF and the MJCF with MuJoCo's check."""

from __future__ import annotations

from pathlib import Path

from rich.table import Table

from excite_cli.console.tables import titled_table
from excite_cli.workflows.identify import IdentifyRun


def _fit_note(run: IdentifyRun, kind: str) -> str:
    """Why the model file's fit is not the reported one, when it is not."""
    report = run.report
    if report.fit_choice.is_consistent:
        return ""
    return (
        f" ({kind} needs physical bodies: the reported model is {report.fit_choice.name}, the consistent fit's "
        f"validation error {report.relative_consistent.mean():.1f} % against {report.relative_after.mean():.1f} %)"
    )


def urdf_written(run: IdentifyRun) -> str:
    """What ``--urdf-out`` wrote: its fit (always the physically consistent one) and how well its RNEA
    reproduces the identified torques."""
    return (
        f"wrote {run.urdf} from the physically consistent fit{_fit_note(run, 'a URDF')}: its RNEA matches that fit's "
        f"rigid-body torques to {run.urdf_deviation:.1e} Nm"
    )


def mjcf_written(run: IdentifyRun) -> list[Table | str]:
    """What ``--mjcf-out`` wrote and MuJoCo's check of it: the joint fields, the validation errors of
    excite's model, of its part the MJCF holds and of MuJoCo's, and what the MJCF cannot hold."""
    model, check, joints = run.mjcf, run.mujoco, run.report.joints
    fields = titled_table(
        "MJCF: per joint, the fields written and the validation error [%]",
        ("joint", "armature [kg·m²]", "damping [Nm·s/rad]", "frictionloss [Nm]")
        + ("excite", "excite, MJCF part", "MuJoCo"),
        [
            (
                name,
                *(f"{model.fields.get((name, a), 0.0):.4g}" for a in ("armature", "damping", "frictionloss")),
                *(f"{x[j]:.2f}" for x in (check.relative_excite, check.relative_written, check.relative_mujoco)),
            )
            for j, name in enumerate(joints)
        ],
        f"mean: excite {check.relative_excite.mean():.2f} %, its MJCF part {check.relative_written.mean():.2f} %, "
        f"MuJoCo {check.relative_mujoco.mean():.2f} %",
    )
    share = dict(check.unwritten)
    lines = [
        f"wrote {Path(model.path)} from the physically consistent fit{_fit_note(run, 'an MJCF')}; MuJoCo's mj_inverse "
        f"matches excite's rigid body, armature and damping to {check.rigid:.1e} of the largest torque, its "
        f"frictionloss excite's Coulomb friction to {check.friction:.1e} where both are saturated "
        f"(they differ by more than 1 % of it on {check.friction_differs:.1f} % of the samples: velocity reversals)",
        *(f"MJCF: {note}" for note in model.notes),
    ]
    for term, coefficient, value, why in model.unwritten:
        label = term.label(joints)
        lines.append(
            f"not in the MJCF ({why}): {label} {coefficient} = {value:.4g}, "
            f"{share.get(label, float('nan')):+.2f} points of validation error without it"
        )
    return [fields, *lines]
