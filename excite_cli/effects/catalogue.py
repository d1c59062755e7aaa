"""Every effect the rigid-body model may lack, one :class:`~excite_cli.effects.record.Effect` record
each, for identification and design alike: adding an effect is adding a record (a design holds those
with ``slopes``). Each is a block of extra regressor columns for one joint, linear in its
coefficients (τ_j += Σ c_k f_k(q_j, q̇_j, q̈_j)); a motor's act in its coordinate s = N q and reach
joint m's row times N_m.

v_c (a smooth sign, 0.01 rad/s by default) is the config's. The position-dependent effects
(``position``) are guarded: outside the q range the fit data covered they hold their value at its
nearer end instead of extrapolating a spring or a harmonic fitted to a narrower motion. Stribeck and
held friction are nonlinear in a shape parameter, their velocity: each is a family of candidates, one
per value of a log-spaced grid (``SHAPE_GRID``), and the selection keeps at most one member per
joint, the one the cross-validated error prefers (a profile search over the shape, scored on the fit
data only). Direction-dependent Coulomb and Stribeck refine Coulomb friction, direction-dependent
viscous refines viscous: they are candidates for a joint only once the effect they refine is in its
model (``requires``). Held friction depends on the motion's history (the samples must be in time
order): s_last is the sign of the last motion faster than v_h, so after a reversal the friction keeps
its old sign until the joint really moves (presliding, stiction). Load-dependent Coulomb friction is
two-stage: τ_rigid is the rigid-body prediction of a first fit (geared joints whose friction grows
with the gear load). An offset is one constant per fitted run (a torque sensor or current amplifier
is zeroed per run); a run the fit never saw gets the mean of the fitted runs' offsets; a design holds
it as one column of ones. A motor that turns with several joints (a coupled wrist: s = q5 + q6) is
one effect, ``motor``: its rotor inertia, Coulomb and viscous friction in the motor coordinate enter
and leave the model together, as the physical motor has all three.
(Friction models: Armstrong-Hélouvry, Dupont, Canudas de Wit, Automatica 1994; load-dependent
friction: Hamon, Gautier, Garrec, IROS 2011.)
"""

from __future__ import annotations

import numpy as np

from excite_cli.effects.record import Effect, combined, held_sign


def _none(s):
    return np.zeros_like(s.qd)


def _one(s):
    return np.ones_like(s.qd)


_COULOMB = Effect(
    "coulomb",
    ("Fc",),
    ("Nm",),
    lambda s: [s.sign],
    motor=True,
    slopes=lambda s: ((1.0 - s.sign**2) / s.coulomb_velocity, _none(s)),
)
_VISCOUS = Effect(
    "viscous", ("Fv",), ("Nm·s/rad",), lambda s: [s.qd], motor=True, slopes=lambda s: (_one(s), _none(s)), per=1
)
_ARMATURE = Effect(
    "armature", ("Ia",), ("kg·m²",), lambda s: [s.qdd], motor=True, slopes=lambda s: (_none(s), _one(s)), per=2
)

#: Every candidate effect, by name (in the order configs and reports list them).
EFFECTS = {
    e.name: e
    for e in (
        _COULOMB,
        Effect("coulomb_asymmetric", ("Fa",), ("Nm",), lambda s: [np.abs(s.sign)], requires="coulomb"),
        _VISCOUS,
        Effect("viscous_asymmetric", ("Fva",), ("Nm·s/rad",), lambda s: [np.abs(s.qd)], requires="viscous"),
        Effect(
            "stribeck",
            ("Fs",),
            ("Nm",),
            lambda s: [s.sign * np.exp(-((s.qd / s.shape) ** 2))],
            requires="coulomb",
            shape="v_s",
            shape_field="stribeck_velocity",
        ),
        Effect(
            "held", ("Fh",), ("Nm",), lambda s: [held_sign(s.qd, s.shape)], shape="v_h", shape_field="held_velocity"
        ),
        Effect("load_coulomb", ("Fl",), ("Nm/Nm",), lambda s: [np.abs(s.rigid) * s.sign], two_stage=True),
        _ARMATURE,
        Effect("offset", ("tau0",), ("Nm",), lambda s: [_one(s)], per_run=True, slopes=lambda s: (_none(s), _none(s))),
        Effect("spring", ("k",), ("Nm/rad",), lambda s: [s.q], position=True),
        Effect("gravity_compensator", ("gs", "gc"), ("Nm", "Nm"), lambda s: [np.sin(s.q), np.cos(s.q)], position=True),
        Effect("position_2", ("gs2", "gc2"), ("Nm", "Nm"), lambda s: [np.sin(2 * s.q), np.cos(2 * s.q)], position=True),
        combined("motor", (_ARMATURE, _COULOMB, _VISCOUS), motor=True, coupled=True),
    )
}
EFFECT_NAMES = tuple(EFFECTS)
#: The effects a design holds as columns (each joint's, in this order): those with slopes.
DESIGNED = tuple(name for name, e in EFFECTS.items() if e.designed)
#: Coefficients that no physical joint has negative (dry and viscous friction dissipate, a rotor's
#: inertia is a mass distribution's): every fit keeps them ≥ 0, the search's and the reported ones alike.
NONNEGATIVE = ("Fc", "Fv", "Ia")
#: Default grid of a shape velocity [rad/s]: factors of 2 to 2.5 from 0.02 to 0.5 rad/s.
SHAPE_GRID = (0.02, 0.05, 0.1, 0.2, 0.5)
