"""``campaign.joint_errors`` in a campaign's pose choice (`hil.campaign.chooser`): with "auto", the
default, the calibration poses are chosen for every harmonic order they can carry beside the geometry
and compliance, and the plan's ``identified_parameters`` stays the count the fit always identifies."""

from __future__ import annotations

from hil.campaign.chooser import HARMONICS_PER_ORDER, _design_orders, _parameter_counts
from hil.station.config import default_config, minimum_calibration_poses
from selector.design import minimum_poses


def test_auto_is_the_campaign_default_and_designs_for_every_order_30_poses_carry():
    config = default_config()
    assert config.campaign["joint_errors"] == "auto"
    assert config.campaign["calibration_poses"] == 30
    # 31 geometry and compliance parameters + 3 orders x 12 harmonics = 67: 24 poses identify them
    assert _design_orders(config) == (1, 2, 3)


def test_auto_drops_the_orders_a_short_campaign_cannot_carry():
    config = default_config()
    base = minimum_calibration_poses(config.robot["type"], True, config.payload, config.gravity)[1]
    one = minimum_poses(base + HARMONICS_PER_ORDER)
    assert _design_orders(config, one - 1) == ()
    assert _design_orders(config, one) == (1,)
    assert _design_orders(config, minimum_poses(base + 2 * HARMONICS_PER_ORDER)) == (1, 2)


def test_fixed_orders_and_none_are_taken_as_asked():
    config = default_config()
    assert _design_orders(config.with_overrides(campaign__joint_errors="none")) == ()
    assert _design_orders(config.with_overrides(campaign__joint_errors="2,lost"), 10) == (2,)


def test_the_designed_harmonics_are_not_counted_as_identified_under_auto():
    report = {"parameters": 31 + 24, "unobservable": [],
              "parameter_names": [f"g{i}" for i in range(31)]
              + [f"joint{j}.{kind}{k}" for j in range(1, 7) for k in (1, 2) for kind in ("cos", "sin")]}
    auto = _parameter_counts(report, default_config())
    assert auto["identified_parameters"] == 31 and auto["joint_error_design"] == 24
    fixed = _parameter_counts(report, default_config().with_overrides(campaign__joint_errors="1,2"))
    assert fixed["identified_parameters"] == 55
