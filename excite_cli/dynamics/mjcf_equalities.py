"""An MJCF's equality constraints the model does not represent: joint couplings
(``<equality><joint>``: joint1 follows joint2; ``<equality><tendon>`` of fixed tendons, linear
combinations of joint angles), checked as a URDF's ``<mimic>``
(:func:`~excite_cli.dynamics.urdf_checks.check_couplings`), and closed kinematic chains
(``<connect>``, ``<weld>`` of two bodies), whose joints may not be active."""

from __future__ import annotations

from pathlib import Path

from excite_cli.dynamics.mjcf_compiled import compiled
from excite_cli.dynamics.mjcf_compiled import mjcf_name as _name
from excite_cli.dynamics.urdf_checks import check_couplings
from excite_cli.errors import ExciteError

CONNECT, WELD, JOINT_EQUALITY, TENDON_EQUALITY = 0, 1, 2, 3  # mjtEq
JOINT_WRAP, SITE_OBJECT = 1, 6  # mjtWrap joint (a fixed tendon's), mjtObj site


def mjcf_couplings(path: Path) -> dict[str, tuple[str, str]]:
    """{follower: (leader, how)} of the MJCF's joint couplings: a joint equality (``joint1`` follows
    ``joint2``; ``how``: the polynomial's coefficients in words), and a tendon equality of fixed
    tendons (``<tendon><fixed>``: a linear combination of joint angles; each joint of it but the first
    follows the first)."""
    mj = compiled(path, meshes=False)
    out = {}
    for e in range(mj.neq):
        if mj.eq_type[e] == JOINT_EQUALITY and mj.eq_obj2id[e] >= 0:
            coefficients = " ".join(f"{c:g}" for c in mj.eq_data[e][:5])
            out[_name(mj, "joint", mj.eq_obj1id[e])] = (_name(mj, "joint", mj.eq_obj2id[e]), f"polycoef {coefficients}")
        if mj.eq_type[e] == TENDON_EQUALITY:
            tendons = [t for t in (mj.eq_obj1id[e], mj.eq_obj2id[e]) if t >= 0]
            joints = [j for t in tendons for j in _tendon_joints(mj, t)]
            how = "tendon equality of " + " and ".join(f"'{_name(mj, 'tendon', t)}'" for t in tendons)
            for j in joints[1:]:
                if j != joints[0]:
                    out.setdefault(_name(mj, "joint", j), (_name(mj, "joint", joints[0]), how))
    return out


def _tendon_joints(mj, t: int) -> list[int]:
    """The joints of fixed tendon ``t`` (none for a spatial tendon, which wraps sites and geoms)."""
    wraps = range(mj.tendon_adr[t], mj.tendon_adr[t] + mj.tendon_num[t])
    return [int(mj.wrap_objid[w]) for w in wraps if mj.wrap_type[w] == JOINT_WRAP]


def closed_chains(path: Path) -> list[tuple[str, list[str]]]:
    """(what, joints) of each ``<equality><connect>`` or ``<weld>`` that closes a kinematic chain: the
    two bodies it ties (a site's body; the world when it names one body) and the joints on the tree's
    path between them, which the constraint holds to each other."""
    mj = compiled(path, meshes=False)
    out = []
    for e in range(mj.neq):
        if mj.eq_type[e] not in (CONNECT, WELD):
            continue
        ends = [int(i) for i in (mj.eq_obj1id[e], mj.eq_obj2id[e])]
        if mj.eq_objtype[e] == SITE_OBJECT:
            ends = [int(mj.site_bodyid[i]) if i >= 0 else 0 for i in ends]
        ends = [max(i, 0) for i in ends]
        paths = [_ancestors(mj, b) for b in ends]
        apart = set(paths[0]) ^ set(paths[1])  # the bodies below the common ancestor, on either side
        joints = [
            _name(mj, "joint", j)
            for b in sorted(apart)
            for j in range(mj.body_jntadr[b], mj.body_jntadr[b] + mj.body_jntnum[b])
        ]
        kind = "connect" if mj.eq_type[e] == CONNECT else "weld"
        out.append(
            (f"<equality><{kind}> of bodies '{_name(mj, 'body', ends[0])}' and '{_name(mj, 'body', ends[1])}'", joints)
        )
    return out


def _ancestors(mj, b: int) -> list[int]:
    """Body ``b`` and its ancestors up to the world (excluded)."""
    out = []
    while b > 0:
        out.append(b)
        b = int(mj.body_parentid[b])
    return out


def check_mjcf(path: Path, active: list[str], locked: list[str] = ()) -> None:
    """The ``active`` and ``locked`` joints respect the MJCF's joint couplings (:func:`mjcf_couplings`,
    checked as a URDF's ``<mimic>``), and no active joint is in a closed kinematic chain
    (:func:`closed_chains`; a URDF cannot describe one, and the model is a tree).

    Raises:
        ExciteError: see :func:`~excite_cli.dynamics.urdf_checks.check_couplings`; (``robot.active_joints``)
            an active joint in a closed chain, naming it and the equality.
    """
    check_couplings(mjcf_couplings(path), active, locked)
    for what, joints in closed_chains(path):
        moving = [j for j in joints if j in active]
        if moving:
            raise ExciteError(
                "robot.active_joints",
                f"joint '{moving[0]}' is in a closed kinematic chain ({what}, through "
                f"{', '.join(repr(j) for j in joints)}), which the model (a tree) does not represent",
                moving[0],
                "active joints outside the chain (its joints held)",
            )
