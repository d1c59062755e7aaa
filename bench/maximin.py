"""The maximin-efficiency design, the candidate measured beside the hedge for undeclared noise: the
trajectory whose worse regret over two noise models is smallest.

Two noise models of a lab that declared none, both per joint on the joint's typical torque R_j
(:func:`~excite_cli.design.noise.typical_torques`): *absolute*, σ_j = R_j (a torque sensor's noise,
the same at every instant), and *relative*, σ_j(t) = √((0.1 R_j)² + τ_j(t)²) (a motor current's:
growing with the torque over a floor of a tenth of the typical torque); only ratios between rows
change a design, so these are the bench's two truths up to scale (bench/criteria.py: 2 % of R_j;
2 % of τ over 0.2 % of R_j). A-optimality f_m (``log_trace_inverse``, the log of the RMS parameter
error per unit of noise) under model m, and at each iteration of the sequence:

1. each model's own optimum f_m* (the config's restarts, screening and polish, C₀ the earlier
   iterations' rows weighed by that model),
2. the trajectory minimizing max_m (f_m − f_m*), the larger log regret (Pukelsheim, Optimal Design of
   Experiments, 1993, Sec. 5.16 on maximin efficiency; Dette 1997 for the standardized form), through
   its smooth maximum (1/β) log Σ_m exp(β (f_m − f_m*)), β = :data:`SHARPNESS` (at most log 2 / β
   above the maximum), from the same random starts and from each model's optimum (the criterion is
   multimodal: on the UR10 from the absolute optimum it stops at a local optimum of the relative
   model's, regrets 1.09 / 1.55, where from the relative optimum it ends at 1.22 / 1.20).

Three optimizations per iteration: the price of the two normalizers. A bench candidate, not a design
excite ships: over four robots, two truths and three seeds its worst regret is 1.46 (per iteration) and
1.45 (per sequence), the compound criterion's (:class:`Compound`, w_abs = 0.75) 1.51, against the hedge's
1.32, each leaning to the absolute model (the figures page, "The maximin-efficiency design beside the
hedge").
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from excite_cli.config import NoiseConfig
from excite_cli.design.criterion import Criterion
from excite_cli.design.excitation import Excitation
from excite_cli.design.information import PriorInformation
from excite_cli.design.noise import typical_torques
from excite_cli.design.resolve import build_excitation
from excite_cli.search.earlier_optimum import from_earlier_optimum
from excite_cli.search.engine import Engine
from excite_cli.search.restarts import RestartContext, run_restarts
from excite_cli.search.sequence import polish_kept, run_sequence

#: β [1]: the smooth maximum's sharpness (log regrets; it overstates the maximum by ≤ log 2 / β = 0.7 %).
#: UR10 lab, seed 1, iteration 1, from the relative optimum: β = 30 ends at regrets 1.23 / 1.18 (the
#: smoothing's own imbalance), 100 at 1.22 / 1.20, 300 at 1.28 / 1.29 (SLSQP on a sharper kink).
SHARPNESS = 100.0
#: The relative model's floor, of each joint's typical torque (the bench's truth: 0.2 % under 2 %).
RELATIVE_FLOOR = 0.1


@dataclass
class Maximin:
    """The smooth maximum over noise models of f_m(α) − f_m*, as the optimizer asks a criterion.

    Attributes:
        parts: one criterion per noise model (each with its own C₀).
        optima: f_m* (m,), each model's own optimum at this iteration.
        prior: the first part's C₀ (what the optimizer reads of it); None (``replace(…, prior=None)``,
            the trajectory's own criterion the optimizer scales by): every part without its C₀.
    """

    parts: tuple[Criterion, ...]
    optima: tuple[float, ...]
    prior: PriorInformation | None = None

    def __post_init__(self) -> None:
        if self.prior is None:
            self.parts = tuple(replace(p, prior=None) for p in self.parts)
        self.prior = self.parts[0].prior

    @property
    def objective(self):
        """The parts' criterion record (A-optimality: not of the extreme singular values, so the
        optimizer takes value and gradient as they are)."""
        return self.parts[0].objective

    def _smooth_max(self, values: list[float]) -> tuple[float, np.ndarray]:
        """The smooth maximum of the log regrets f_m − f_m* and its weights (m,) (the softmax: its
        gradient in the f_m)."""
        g = np.array(values) - np.array(self.optima)
        top = g.max()
        w = np.exp(SHARPNESS * (g - top))
        return float(top + np.log(w.sum()) / SHARPNESS), w / w.sum()

    def value(self, alpha: np.ndarray, from_gram: bool = False) -> float:
        """The smooth maximum at α (n, 2N+1) [1, log regret]; ``from_gram`` as the parts take it
        (:meth:`~excite_cli.design.criterion.Criterion.value`)."""
        return self._smooth_max([p.value(alpha, from_gram) for p in self.parts])[0]

    def value_and_gradient(self, alpha: np.ndarray) -> tuple[float, np.ndarray]:
        """The smooth maximum at α (n, 2N+1) and its gradient (n, 2N+1): the softmax-weighted sum of
        the parts' analytic gradients (Eqs. 45–49 each)."""
        both = [p.value_and_gradient(alpha) for p in self.parts]
        value, w = self._smooth_max([v for v, _ in both])
        return value, sum(wk * g for wk, (_, g) in zip(w, both))

    def regrets(self, alpha: np.ndarray) -> np.ndarray:
        """exp(f_m − f_m*) (m,): each model's regret at α."""
        return np.exp(np.array([p.value(alpha) for p in self.parts]) - np.array(self.optima))


@dataclass
class Compound(Maximin):
    """The compound criterion Σ_m w_m f_m(α): the weighted mean of the models' log criteria (with
    ``optima`` zero; a normalizer would only add a constant in log space, so none is needed).

    Attributes:
        weights: w_m (m,), summing to 1 (the absolute model's first).
    """

    weights: tuple[float, ...] = (0.5, 0.5)

    def _smooth_max(self, values: list[float]) -> tuple[float, np.ndarray]:
        """Σ_m w_m (f_m − f_m*) and its weights (m,) (its gradient in the f_m)."""
        w = np.array(self.weights)
        return float(w @ (np.array(values) - np.array(self.optima))), w


@dataclass
class _MaximinExcitation(Excitation):
    """An excitation whose design criterion is :class:`Maximin` (set per iteration); in this process
    only (a pool's workers would build the library's)."""

    maximin: Maximin | None = None

    def criterion(self, prior=None, objective=None, scaling=None, weighed=True):
        """The maximin (its own C₀ per model, whatever ``prior`` says) where the optimizer asks for the
        design's criterion; any other criterion as :meth:`Excitation.criterion` builds it."""
        if weighed and objective is None and scaling is None:
            return self.maximin
        return super().criterion(prior, objective, scaling, weighed)


def noise_models(problem) -> list[NoiseConfig]:
    """The absolute and the relative model on the joints' typical torques (module docstring)."""
    problem.noise = NoiseConfig(absolute=1.0)
    typical = typical_torques(build_excitation(problem))
    joints = problem.robot.active_joints
    return [
        NoiseConfig(absolute=dict(zip(joints, typical.tolist())), relative=0.0),
        NoiseConfig(absolute=dict(zip(joints, (RELATIVE_FLOOR * typical).tolist())), relative=1.0),
    ]


def _iteration(excitation, engine, k: int, seed: int, prior: PriorInformation, earlier: list, starts=()) -> object:
    """The kept restart of iteration k as run_sequence finds it (restarts, polish, the earlier optima),
    with restarts from ``starts`` (α each) beside the random ones."""
    context = RestartContext.starting(excitation, engine, k, seed, prior)
    runs = run_restarts(context)
    index = max(r.index for r in runs) + 1
    runs += context.run([context.task(index + i, start) for i, start in enumerate(starts)], None)
    runs, best = polish_kept(context, runs)
    more = from_earlier_optimum(context, runs, best, earlier)
    if len(more) > len(runs):
        runs, best = polish_kept(context, more)
    return best


def maximin_sequence(problem, seed: int, workers: int, normalizers: str = "sequence", log=print) -> list[np.ndarray]:
    """α (n, 2N+1) of each iteration of ``problem``'s sequence, designed by maximin efficiency over
    :func:`noise_models` with optimizer seed ``seed``; each iteration's regrets and optima logged.

    ``normalizers``: ``iteration``, f_m* each model's optimum at this iteration with C₀ the maximin's
    earlier iterations weighed by the model; ``sequence``, the stacked criterion each model's own
    sequence reaches at this iteration (run first, in full), so the regret is the sequence's against
    the design told that model; ``compound:W``, no normalizer: the :class:`Compound` criterion with
    weights (W, 1 − W), W the absolute model's."""
    problem.optimizer.seed = seed
    excitations = []
    for model in noise_models(problem):
        problem.noise = model
        excitations.append(build_excitation(problem))
    own = []
    if normalizers == "sequence":
        for e in excitations:
            with Engine(e, workers) as engine:
                own.append([r.best for r in run_sequence(e, problem.sequence.iterations, seed, engine=engine)])
    first = excitations[0]
    mine = _MaximinExcitation(**{f.name: getattr(first, f.name) for f in fields(Excitation)})
    earlier: list[np.ndarray] = []
    for k in range(1, problem.sequence.iterations + 1):
        priors = [
            PriorInformation.of(np.vstack([e.criterion().regressor(a) for a in earlier] or [np.zeros((0, e.columns))]))
            for e in excitations
        ]
        if normalizers.startswith("compound"):
            w = float(normalizers.split(":")[1])
            parts = tuple(e.criterion(p) for e, p in zip(excitations, priors))
            mine.maximin = Compound(parts, (0.0, 0.0), priors[0], (w, 1.0 - w))
            with Engine(mine, 1) as engine:
                best = _iteration(mine, engine, k, seed, priors[0], earlier)
            log(f"  iteration {k}: compound {best.objective:.4f} (kept restart {best.index})")
            earlier.append(best.alpha)
            continue
        if normalizers == "sequence":
            optima = [runs[k - 1] for runs in own]
        else:
            optima = []
            for e, prior in zip(excitations, priors):
                with Engine(e, workers) as engine:
                    optima.append(_iteration(e, engine, k, seed, prior, earlier))
        values = tuple(r.objective for r in optima)
        mine.maximin = Maximin(tuple(e.criterion(p) for e, p in zip(excitations, priors)), values, priors[0])
        with Engine(mine, 1) as engine:
            best = _iteration(mine, engine, k, seed, priors[0], earlier, [r.alpha for r in optima])
        regrets = " / ".join(f"{x:.3f}" for x in mine.maximin.regrets(best.alpha))
        log(f"  iteration {k}: optima {values[0]:.4f} / {values[1]:.4f}, regrets {regrets} (kept restart {best.index})")
        earlier.append(best.alpha)
    return earlier
