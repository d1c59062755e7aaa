"""What rehearse prints: the joints' tracking and torques, a standing robot's balance beside PD alone, and
the verdict naming what would not play safely."""

from dataclasses import replace

from conftest import made_rehearsal

from excite_cli.console.rehearsal import rehearsal


def text(items) -> list[str]:
    return [item for item in items if isinstance(item, str)]


def test_a_standing_robot_s_balance_is_printed_with_pd_alone_beside_it():
    lines = text(rehearsal(made_rehearsal()))
    [fed] = [line for line in lines if line.startswith("with the held joints' feed-forward: stands")]
    assert "at least 30.0 mm inside" in fed and "RMS gap to excite's ZMP 0.0 mm" in fed
    [alone] = [line for line in lines if line.startswith("PD alone:")]
    assert "at least 60.0 mm inside" in alone and "RMS gap to excite's ZMP 30.0 mm" in alone  # 3 cm apart
    assert lines[-1] == "every iteration played: 1 of 1"


def test_a_fall_or_a_torque_over_its_limit_is_the_verdict():
    assert "FALLS" in " ".join(text(rehearsal(made_rehearsal(fell=True))))
    lines = text(rehearsal(made_rehearsal(standing=False, tau_peak=2.5)))
    assert "over its limit: b 2.50 N·m against 2 N·m" in lines
    assert lines[-1] == "refused: iteration 1 would not play safely" and "contacts: none" in lines


def test_a_speed_the_export_refuses_is_named_with_its_limit_and_refused():
    done = made_rehearsal(standing=False)
    it = done.iterations[0]
    it.export = replace(it.export, max_violation=0.5, worst="joint_limits: velocity of b at 1.5 of its half-range")
    lines = text(rehearsal(done))
    assert "excite export refuses this speed (played here all the same): joint_limits: velocity of b" in lines[-3]
    assert lines[-1] == "refused: iteration 1 would not play safely"
