"""The ``rehearsal`` section: defaults a lab starts from, per-joint gains, and gains that are no PD refused."""

import pytest
from pydantic import ValidationError

from excite_cli.config.rehearsal import GainsConfig, RehearsalConfig


def test_defaults_and_per_joint_gains():
    c = RehearsalConfig(held_gains={"stiffness": 800, "damping": 30, "per_joint": {"knee": [1500, 60]}})
    assert c.rate == 1000.0 and c.held_feedforward and c.joint_losses is None
    assert c.active_gains.of("elbow") == (200.0, 10.0)
    assert c.held_gains.of("knee") == (1500.0, 60.0) and c.held_gains.of("hip") == (800.0, 30.0)


@pytest.mark.parametrize(
    "data, field",
    [({"stiffness": 0, "damping": 1}, "stiffness"), ({"stiffness": 1, "damping": -1}, "damping")],
)
def test_gains_that_are_no_pd_are_refused_naming_the_field(data, field):
    with pytest.raises(ValidationError, match=field):
        GainsConfig(**data)
    with pytest.raises(ValidationError, match="rate"):
        RehearsalConfig(rate=0)
