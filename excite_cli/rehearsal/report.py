"""What a rehearsal found: per iteration the export played, what MuJoCo measured with the lab's controller
(and with PD alone on a standing robot's held joints), and whether it would play safely."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from excite_cli.config.rehearsal import RehearsalConfig
from excite_cli.rehearsal.playing import Played
from excite_cli.storage.export import Export


@dataclass
class IterationRehearsal:
    """One iteration played.

    Attributes:
        iteration: the result's iteration k.
        export: the samples played (``excite export``'s at the controller's rate).
        played: what MuJoCo measured with the configured controller.
        alone: the same with PD alone on the held joints (a standing robot whose controller adds the
            held joints' feed-forward), else None.
        effort: (n,) the active joints' torque limits [N·m] (inf where the file gives none).
        held_effort: (h,) the held joints' [N·m], in ``held_names``' order (0: none given).
        predicted: (S, 2) excite's zero-moment point at the samples [m] (standing), else None.
        held_names: (h,) the held joints, the columns of ``played.held_tau``.
    """

    iteration: int
    export: Export
    played: Played
    alone: Played | None
    effort: np.ndarray
    held_effort: np.ndarray
    predicted: np.ndarray | None = None
    held_names: tuple[str, ...] = ()

    @property
    def over_limit(self) -> list[tuple[str, float, float]]:
        """(joint, peak [N·m], limit [N·m]) of every joint whose applied torque passed its limit."""
        names = [*self.export.joint_names, *self.held_names]
        peaks = np.r_[np.abs(self.played.tau).max(axis=0), np.abs(self.played.held_tau).max(axis=0, initial=0.0)]
        limits = np.r_[self.effort, self.held_effort]
        return [(n, p, lim) for n, p, lim in zip(names, peaks, limits) if 0 < lim < p]

    @property
    def refused(self) -> str | None:
        """The limit ``excite export`` refuses these samples for (played here all the same), in words."""
        return self.export.worst if self.export.max_violation > 0.0 else None

    @property
    def failed(self) -> bool:
        """It fell, a torque passed its limit, a contact appeared (with the configured controller) or the
        export refuses the samples."""
        return self.played.fell or bool(self.over_limit) or bool(self.played.contacts) or bool(self.refused)


@dataclass
class Rehearsal:
    """What ``excite rehearse`` played and wrote.

    Attributes:
        result: the optimize result.
        controller: the ``rehearsal`` section used.
        iterations: one :class:`IterationRehearsal` per iteration played.
        robot_file: the file MuJoCo compiled (the URDF or ``--mjcf``).
        notes: what the model left out or changed, in words.
        recordings: the CSV files ``--record`` wrote.
        plot: the PNG written.
    """

    result: Path
    controller: RehearsalConfig
    iterations: list[IterationRehearsal]
    robot_file: Path
    notes: list[str] = field(default_factory=list)
    recordings: list[Path] = field(default_factory=list)
    plot: Path | None = None

    @property
    def failed(self) -> bool:
        """Some iteration fell, passed a torque limit or touched something."""
        return any(r.failed for r in self.iterations)

    @property
    def standing(self) -> bool:
        """The robot stood on its soles (a floating base)."""
        return bool(self.iterations) and self.iterations[0].played.drop is not None
