"""How far a linear model of a compliant stance brings excite's ZMP to MuJoCo's centre of pressure: an
experiment for issue 58 (not in the optimizer). The G1's legs and waist held by a PD (--stiffness,
--damping) sway under the arms' motion; excite's ZMP assumes them rigid and misses MuJoCo's centre of
pressure by 25–44 mm (docs/figures.md, "Balance in MuJoCo").

The model: pinocchio's G1 with its free flyer and all 29 joints, both feet fixed, the held joints as
springs about their locked values, linearized at the home posture. Its coordinates are the null space
of both feet's Jacobians over the base and the held joints (9 of 21); its stiffness the Hessian (finite
differences, the feet closed by Newton steps) of the gravity potential plus ½ K δ² on that closed
chain; its mass and damping the projected mass matrix and PD damping; its forcing the base and held
rows of RNEA with the arms moving, less the static load. Newmark's average acceleration integrates it
over the played samples, and the ground wrench gains m Δc̈ and ΔL̇ + c × m Δc̈ − Δc × m g. Printed per
iteration of a result: MuJoCo's CoP margin, the rigid and the compliant prediction's margins and RMS
gaps, with MuJoCo's default soft contacts and with stiff ones (solref 0.002 s), and both models' sway
frequencies.

    .venv/bin/python bench/stance_compliance.py [--result results/g1_arms.h5]
"""

from __future__ import annotations

import excite_cli  # noqa: F401  (before NumPy: the kernels of the command line, excite_cli/kernels.py)

# isort: split

import argparse
from pathlib import Path

import numpy as np
import pinocchio as pin
from balance import setup, sway
from scipy.linalg import null_space

from excite_cli.constraints.zmp import zero_moment_point
from excite_cli.design.mujoco_stance import TIMESTEP, Stance, play_standing, standing_model
from excite_cli.design.playback import plan_playback
from excite_cli.storage.results import read_alphas

ROOT = Path(__file__).resolve().parent.parent
FEET = ("left_ankle_roll_link", "right_ankle_roll_link")


class CompliantStance:
    """The linear model of the module docstring for the robot of ``excitation`` (a G1 problem)."""

    def __init__(self, urdf: Path, excitation, stiffness: float, damping: float):
        full = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
        self.full, self.data = full, full.createData()
        arms = excitation.robot.joint_names
        self.arm_q = np.array([full.idx_qs[full.getJointId(n)] for n in arms])
        self.arm_v = np.array([full.idx_vs[full.getJointId(n)] for n in arms])
        held = np.array([full.idx_vs[full.getJointId(n)] for n in full.names[2:] if n not in arms])
        self.x = np.r_[np.arange(6), held]  # base and held joints' velocities
        self.q0 = pin.neutral(full)
        self.q0[self.arm_q] = excitation.home
        self.feet = [full.getFrameId(n) for n in FEET]
        self.N = null_space(self._feet_jacobian(self.q0)[:, self.x])
        pin.framesForwardKinematics(full, self.data, self.q0)
        self.foot0 = [self.data.oMf[f].copy() for f in self.feet]
        self.stiffness = stiffness
        M = pin.crba(full, self.data, self.q0)
        M = np.triu(M) + np.triu(M, 1).T
        self.M = self.N.T @ M[np.ix_(self.x, self.x)] @ self.N
        self.D = self.N.T @ np.diag(np.r_[np.zeros(6), np.full(held.size, damping)]) @ self.N
        self.K = self._hessian()
        pin.ccrba(full, self.data, self.q0, np.zeros(full.nv))
        self.Ag = self.data.Ag.copy()
        self.Jcom = pin.jacobianCenterOfMass(full, self.data, self.q0)
        self.c0, self.mass = self.data.com[0].copy(), self.data.mass[0]
        self.static = pin.rnea(full, self.data, self.q0, np.zeros(full.nv), np.zeros(full.nv))[self.x]

    def _feet_jacobian(self, q: np.ndarray) -> np.ndarray:
        pin.computeJointJacobians(self.full, self.data, q)
        pin.updateFramePlacements(self.full, self.data)
        return np.vstack([pin.getFrameJacobian(self.full, self.data, f, pin.LOCAL) for f in self.feet])

    def _configuration(self, x: np.ndarray) -> np.ndarray:
        v = np.zeros(self.full.nv)
        v[self.x] = x
        return pin.integrate(self.full, self.q0, v)

    def _potential(self, eta: np.ndarray) -> float:
        """Gravity's potential plus the springs' on the closed chain, at reduced coordinates ``eta``."""
        x = self.N @ eta
        for _ in range(20):  # Newton steps back onto both feet's placements
            q = self._configuration(x)
            pin.framesForwardKinematics(self.full, self.data, q)
            error = [pin.log6(self.data.oMf[f].actInv(o)).vector for f, o in zip(self.feet, self.foot0)]
            if np.abs(error).max() < 1e-13:
                break
            x = x + np.linalg.lstsq(self._feet_jacobian(q)[:, self.x], np.concatenate(error), rcond=None)[0]
        held = x[6:]
        return pin.computePotentialEnergy(self.full, self.data, q) + 0.5 * self.stiffness * held @ held

    def _hessian(self, step: float = 1e-4) -> np.ndarray:
        n = self.N.shape[1]
        E, H = np.eye(n) * step, np.zeros((n, n))
        for i in range(n):
            for j in range(i, n):
                V = [self._potential(si * E[i] + sj * E[j]) for si, sj in ((1, 1), (1, -1), (-1, 1), (-1, -1))]
                H[i, j] = H[j, i] = (V[0] - V[1] - V[2] + V[3]) / (4 * step**2)
        return H

    def frequencies(self) -> np.ndarray:
        """The model's sway frequencies [Hz], lowest first."""
        return np.sort(np.sqrt(np.abs(np.linalg.eigvals(np.linalg.solve(self.M, self.K)).real))) / (2 * np.pi)

    def wrench_change(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, dt: float) -> np.ndarray:
        """(T, 6) what the sway adds to the ground wrench at the arms' samples q, q̇, q̈ (T, n), every ``dt`` [s]."""
        qq, vv, aa = self.q0.copy(), np.zeros(self.full.nv), np.zeros(self.full.nv)
        forcing = []
        for sample in zip(q, qd, qdd):
            qq[self.arm_q], vv[self.arm_v], aa[self.arm_v] = sample
            forcing.append(-(pin.rnea(self.full, self.data, qq, vv, aa)[self.x] - self.static) @ self.N)
        n = self.N.shape[1]
        eta, rate, accel = np.zeros(n), np.zeros(n), np.linalg.solve(self.M, forcing[0])
        stiff = self.K + 2 / dt * self.D + 4 / dt**2 * self.M
        accelerations, positions = [accel], [eta]
        for u in forcing[1:]:  # Newmark, average acceleration
            rhs = u + self.M @ (4 / dt**2 * eta + 4 / dt * rate + accel) + self.D @ (2 / dt * eta + rate)
            new = np.linalg.solve(stiff, rhs)
            rate, accel, eta = 2 / dt * (new - eta) - rate, 4 / dt**2 * (new - eta) - 4 / dt * rate - accel, new
            accelerations.append(accel)
            positions.append(eta)
        X, XDD = np.array(positions) @ self.N.T, np.array(accelerations) @ self.N.T
        dc, dcdd = X @ self.Jcom[:, self.x].T, XDD @ self.Jcom[:, self.x].T
        force = self.mass * dcdd
        moment = XDD @ self.Ag[3:, self.x].T + np.cross(self.c0, force)
        moment -= np.cross(dc, self.mass * self.full.gravity.linear)
        return np.hstack([force, moment])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--config", type=Path, default=ROOT / "configs" / "g1_arms.yaml")
    parser.add_argument("--result", type=Path, default=ROOT / "results" / "g1_arms.h5")
    parser.add_argument("--stiffness", type=float, default=1000.0, help="PD stance [Nm/rad]")
    parser.add_argument("--damping", type=float, default=40.0, help="PD stance [Nm·s/rad]")
    args = parser.parse_args()
    problem, excitation, zmp, urdf, locked = setup(args.config)
    joints, robot = excitation.robot.joint_names, excitation.robot
    stance = CompliantStance(urdf, excitation, args.stiffness, args.damping)
    print(f"model sway frequencies: {' '.join(f'{f:.2f}' for f in stance.frequencies()[:3])} Hz")
    for label, solref in (("default contacts", None), ("stiff contacts (solref 0.002 s)", 0.002)):
        model = standing_model(
            urdf, joints, locked, problem.constraints.zmp.support_links, Stance(args.stiffness, args.damping)
        )
        if solref is not None:
            model.geom_solref[:, 0] = solref
        print(f"{label}: MuJoCo sway {' '.join(f'{f:.2f}' for f in sway(model, joints, excitation.home, locked))} Hz")
        for k, alpha in sorted(dict(read_alphas(args.result)).items()):
            _, q, qd, qdd = plan_playback(excitation, alpha).sample(1.0 / TIMESTEP)
            tau = np.array([robot.torques(*x) for x in zip(q, qd, qdd)])
            run = play_standing(model, joints, locked, q, qd, tau)
            wrench = zmp.wrenches(q, qd, qdd)
            rigid = zero_moment_point(wrench, zmp.polygon.height)
            compliant = zero_moment_point(wrench + stance.wrench_change(q, qd, qdd, TIMESTEP), zmp.polygon.height)
            gap = [1000 * np.sqrt(np.nanmean(np.sum((run.cop - p) ** 2, axis=1))) for p in (rigid, compliant)]
            margins = [1000 * zmp.polygon.margins(p).min() for p in (rigid, compliant)]
            print(
                f"  iteration {k}: MuJoCo CoP margin {1000 * run.margin.min():.1f} mm; rigid ZMP {margins[0]:.1f} mm "
                f"(RMS gap {gap[0]:.1f} mm), compliant {margins[1]:.1f} mm (RMS gap {gap[1]:.1f} mm)",
                flush=True,
            )


if __name__ == "__main__":
    main()
