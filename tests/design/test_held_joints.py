"""The held joints' feed-forward of the standing G1, as ``export`` writes it to CSV, against the floating
base's equations of motion built independently (pinocchio's CRBA and nonlinear effects, the contact
Jacobians of frames placed at the soles' sphere bottoms read from the URDF): every row balanced with
the contact forces the export used, each sole's centre of pressure inside its own contact points, each
force inside its friction cone; where the least-norm split leaves a cone, the cone-constrained split
is the same quadratic program's optimum as cvxpy finds it."""

import cvxpy as cp
import numpy as np
import pinocchio as pin
import pytest
from conftest import CONFIGS
from scipy.spatial import ConvexHull

from excite_cli.config_file import load_problem, with_overrides
from excite_cli.design.held_joints import held_joints
from excite_cli.design.resolve import build_excitation
from excite_cli.dynamics.robot_files import resolve_urdf
from excite_cli.storage.export import Played, export_trajectory
from excite_cli.storage.export_files import write_export

FEET = ("left_ankle_roll_link", "right_ankle_roll_link")


@pytest.fixture(scope="module")
def g1():
    problem = load_problem(CONFIGS / "g1_arms.yaml")
    excitation = build_excitation(problem)
    held = held_joints(problem.robot, problem.folder, problem.constraints, excitation.robot)
    return problem, excitation, held


@pytest.fixture(scope="module")
def exported(g1, tmp_path_factory):
    """A random motion of the G1's arms exported at 100 Hz to CSV, read back by column name."""
    problem, excitation, held = g1
    alpha = excitation.random_start(np.random.default_rng(2))
    export = export_trajectory(
        excitation, alpha, Played(tmp_path_factory.mktemp("g1") / "r.h5", 1, 100.0, 1, 1.0), held
    )
    path = write_export(tmp_path_factory.mktemp("csv") / "g1.csv", export, "csv")
    table = np.genfromtxt(path, delimiter=",", names=True)
    return export, table, path


def test_the_g1_csv_reads_with_numpy_and_pandas_and_names_the_held_peak_and_the_split(exported):
    import pandas

    export, table, path = exported
    frame = pandas.read_csv(path, comment="#")
    held = [f"tau_{j}_Nm" for j in export.held.joint_names]
    assert len(held) == 15 and list(frame.columns)[-15:] == held == list(table.dtype.names)[-15:]
    k, share = export.held.peak()
    peak = np.abs(frame[held[k]]).max()
    notes = [line for line in path.read_text().splitlines() if line.startswith("#")]
    said = f"# held joints' peak: {export.held.joint_names[k]} {peak:.4g} Nm, {100 * share:.0f} % of its URDF limit"
    assert any(n.startswith(said) for n in notes), notes
    assert any("the ground wrench split as the least-norm forces" in n and "friction cone (mu 0.5)" in n for n in notes)


def _sole_points(urdf) -> list[np.ndarray]:
    """Each foot's sphere bottoms in the world frame, from the URDF's collision spheres (base at the
    origin, every joint at 0)."""
    model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    share = str(urdf.parents[4])  # package://example-robot-data/robots/...
    geometry = pin.buildGeomFromUrdf(model, str(urdf), pin.GeometryType.COLLISION, package_dirs=[share])
    data, gdata = model.createData(), geometry.createData()
    pin.updateGeometryPlacements(model, data, geometry, gdata, pin.neutral(model))
    feet = []
    for foot in FEET:
        spheres = [
            (gdata.oMg[i].translation, o.geometry.radius)
            for i, o in enumerate(geometry.geometryObjects)
            if model.frames[o.parentFrame].name == foot
        ]
        feet.append(np.array([c - [0.0, 0.0, r] for c, r in spheres]))
    return feet


def test_the_csv_s_held_torques_balance_the_floating_base_s_equations_of_motion(g1, exported):
    problem, excitation, _ = g1
    export, table, _ = exported
    held = export.held
    assert len(held.joint_names) == 15 and all(f"tau_{j}_Nm" in table.dtype.names for j in held.joint_names)
    urdf = resolve_urdf(problem.robot, problem.folder)[0]
    feet = _sole_points(urdf)
    np.testing.assert_allclose(held.points, np.vstack(feet), atol=1e-9)

    model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    standing = model.createData()
    pin.forwardKinematics(model, standing, pin.neutral(model))  # the held joints at 0, as the feet stay
    frames = []
    for foot, points in zip(FEET, feet):
        parent = model.getFrameId(foot)
        joint = model.frames[parent].parentJoint
        for i, p in enumerate(points):
            placement = standing.oMi[joint].actInv(pin.SE3(np.eye(3), p))
            frames.append(model.addFrame(pin.Frame(f"{foot}_{i}", joint, parent, placement, pin.FrameType.OP_FRAME)))
    data = model.createData()
    v_of = {name: model.idx_vs[model.getJointId(name)] for name in model.names[2:]}
    q_of = {name: model.idx_qs[model.getJointId(name)] for name in model.names[2:]}
    for k in range(0, len(table), 7):
        q, v, a, tau = pin.neutral(model), np.zeros(model.nv), np.zeros(model.nv), np.zeros(model.nv)
        for name in excitation.robot.joint_names:
            q[q_of[name]], v[v_of[name]] = table[f"q_{name}_rad"][k], table[f"qd_{name}_rad_s"][k]
            a[v_of[name]], tau[v_of[name]] = table[f"qdd_{name}_rad_s2"][k], table[f"tau_{name}_Nm"][k]
        for name in held.joint_names:
            tau[v_of[name]] = table[f"tau_{name}_Nm"][k]
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        h = pin.nonLinearEffects(model, data, q, v)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        contact = sum(
            pin.getFrameJacobian(model, data, f, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:3].T @ force
            for f, force in zip(frames, held.forces[k])
        )
        residual = M @ a + h - tau - contact
        assert np.abs(residual[:6]).max() < 1e-6  # the base: N and N·m
        assert np.abs(residual[6:]).max() < 1e-6  # every joint, held and active [Nm]

    forces, mu = held.forces, problem.constraints.zmp.friction
    assert np.all(np.hypot(forces[..., 0], forces[..., 1]) <= mu * forces[..., 2] * (1 + 1e-9))
    start = 0
    for points in feet:
        f = forces[:, start : start + len(points)]
        start += len(points)
        cop = np.einsum("sc,cx->sx", f[..., 2], points[:, :2]) / f[..., 2].sum(axis=1, keepdims=True)
        hull = ConvexHull(points[:, :2])
        assert np.all(cop @ hull.equations[:, :2].T + hull.equations[:, 2] <= 1e-9)


def test_where_the_least_norm_split_leaves_a_cone_the_split_is_the_cone_constrained_optimum(g1):
    """A ground wrench whose centre of pressure lies 5 mm inside the soles' front left corner: the
    least-norm forces pull on the right heel; the split keeps every force pushing, inside its cone, and
    is the optimum cvxpy finds for min ‖f‖² under the same balance and cones. Beyond the corner no
    split exists."""
    _, _, held = g1
    points, weight = held.points, 350.0
    corner = points[:, :2].max(axis=0) - [0.0, 0.005]  # the left sole's outer front sphere's y

    def wrench(inside: float) -> np.ndarray:
        force = np.array([3.0, -2.0, weight])
        return np.r_[force, np.cross([*(corner - inside), points[0, 2]], force)]

    inside = wrench(0.005)
    assert not held.in_cones(held.A_pinv @ inside)
    f, found = held.contact_forces(inside)
    assert found
    x = cp.Variable(3 * len(points))
    cones = [cp.SOC(held.friction * x[3 * c + 2], x[3 * c : 3 * c + 2]) for c in range(len(points))]
    cp.Problem(cp.Minimize(cp.sum_squares(x)), [held.A @ x == inside] + cones).solve()
    np.testing.assert_allclose(f, x.value, atol=1e-4 * weight)
    np.testing.assert_allclose(held.A @ f, inside, atol=1e-6)
    assert held.in_cones(f * (1 - 1e-7))
    assert not held.contact_forces(wrench(-0.005))[1]


def test_a_robot_standing_on_a_link_its_active_joints_move_is_refused(g1):
    problem, _, _ = g1
    hands = with_overrides(problem, {"constraints.zmp.support_links": ["left_wrist_yaw_link", "right_wrist_yaw_link"]})
    robot = build_excitation(problem).robot
    with pytest.raises(Exception, match="moved by the active joint 'left_shoulder_pitch_joint'"):
        held_joints(hands.robot, hands.folder, hands.constraints, robot)
