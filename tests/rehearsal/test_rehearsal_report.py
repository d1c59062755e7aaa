"""What a rehearsal found: a torque over its limit names its joint (a joint without a limit never is),
and an iteration fails when it falls, passes a limit or touches something."""

import numpy as np

from excite_cli.rehearsal.playing import Played
from excite_cli.rehearsal.report import IterationRehearsal
from excite_cli.storage.export import Export


def iteration(tau: np.ndarray, effort: np.ndarray, contacts=None, drop=None) -> IterationRehearsal:
    time = np.arange(len(tau)) * 1e-3
    export = Export(["a", "b"], time, tau * 0, tau * 0, tau * 0, tau, 1000.0, 1, 1, [], -1.0, "")
    tilt = None if drop is None else time * 0
    played = Played(
        time, tau * 0, tau * 0, tau, np.zeros((len(tau), 0)), contacts or {}, (), None, None, None, tilt, tilt, drop
    )
    return IterationRehearsal(1, export, played, None, effort, np.zeros(0))


def test_a_torque_over_its_limit_names_the_joint_and_fails():
    tau = np.array([[1.0, -3.0], [2.0, 0.5]])
    assert iteration(tau, np.array([2.5, 2.5])).over_limit == [("b", 3.0, 2.5)]
    assert iteration(tau, np.array([2.5, 2.5])).failed
    assert not iteration(tau, np.array([2.5, np.inf])).failed and not iteration(tau, np.array([2.5, 0.0])).failed


def test_a_contact_or_a_fall_fails():
    tau = np.zeros((2, 2))
    assert iteration(tau, np.ones(2), {("panda_link7", "world"): 0.4}).failed
    assert iteration(tau, np.ones(2), drop=np.array([0.0, 0.06])).failed
    assert not iteration(tau, np.ones(2), drop=np.array([0.0, 0.04])).failed


def test_a_held_joint_over_its_limit_is_named_as_the_played_columns_are():
    tau, time = np.zeros((2, 2)), np.arange(2) * 1e-3
    export = Export(["a", "b"], time, tau, tau, tau, tau, 1000.0, 1, 1, [], -1.0, "")
    held = np.array([[6.0, 100.0], [1.0, 1.0]])  # the waist has no limit in its file
    played = Played(time, tau, tau, tau, held, {}, (), sole_tilt=time, root_tilt=time, drop=time)
    it = IterationRehearsal(1, export, played, None, np.ones(2), np.array([5.0, 0.0]), None, ("knee", "waist"))
    assert it.over_limit == [("knee", 6.0, 5.0)] and it.failed
