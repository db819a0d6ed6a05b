"""The realistic arm's joint errors and lost motion are the sizes `hil.arm.joint_physics` cites."""

from __future__ import annotations

import numpy as np
import pytest

from hil.arm.catalog import ROBOT_NAMES
from hil.arm.geometry import Geometry
from hil.arm.joint_errors import MAX_ORDER
from hil.arm.joint_physics import (
    ARCSEC,
    ECCENTRICITY_SIGMA,
    GEAR_HYSTERESIS,
    INTERPOLATION_ERROR,
    POSE_REPEATABILITY,
    RP_PER_SIGMA,
    SECOND_HARMONIC_RATIO,
    eccentricity_amplitudes,
    graduation_diameters,
    standstill_sigma,
    typical_joint_errors,
    typical_lost_motion,
)
from hil.arm.kinematics import Kinematics
from hil.arm.physical import UNSEEN_WINDUP
from hil.verify.accuracy import pose_accuracy


def test_heidenhains_relation_gives_the_once_per_turn_error() -> None:
    # ±412·e/D arc-seconds: 5 µm on a size-25 gear's 63.5 mm pitch circle is 32.4″
    d = graduation_diameters("ur5e")
    assert d.tolist() == pytest.approx([63.5, 63.5, 63.5, 35.56, 35.56, 35.56])
    assert eccentricity_amplitudes("ur5e")[0] == pytest.approx(412 * 5 / 63.5 * ARCSEC)
    assert abs(ARCSEC - 4.8481e-6) < 1e-9
    assert abs(GEAR_HYSTERESIS - 2.909e-4) < 1e-6  # 1 arc-min


def test_drawn_magnitudes_are_the_cited_ones() -> None:
    """Over many arms each term's spread is what the module docstring says it is."""
    rng = np.random.default_rng(0)
    arms = [typical_joint_errors("ur10e", rng) for _ in range(400)]
    first = eccentricity_amplitudes("ur10e", ECCENTRICITY_SIGMA)
    for j in range(6):
        k1 = np.array([[a.joints[j][0].cos, a.joints[j][0].sin] for a in arms])
        k2 = np.array([[a.joints[j][1].cos, a.joints[j][1].sin] for a in arms])
        assert {a.joints[j][0].order for a in arms} == {1} and {a.joints[j][1].order for a in arms} == {2}
        assert k1.std() == pytest.approx(first[j], rel=0.1)
        assert k2.std() == pytest.approx(SECOND_HARMONIC_RATIO * first[j], rel=0.1)
        high = [a.joints[j][2] for a in arms]
        worst = dict(INTERPOLATION_ERROR)
        assert {h.order for h in high} == set(worst)
        assert all(np.hypot(h.cos, h.sin) <= worst[h.order] * ARCSEC + 1e-15 for h in high)
        assert all(h.order <= MAX_ORDER for h in high)
    lost = np.array([typical_lost_motion("ur10e", rng) for _ in range(400)])
    assert lost.min() >= 0.5 * UNSEEN_WINDUP * GEAR_HYSTERESIS
    assert lost.max() <= 1.5 * UNSEEN_WINDUP * GEAR_HYSTERESIS
    assert lost.mean() == pytest.approx(UNSEEN_WINDUP * GEAR_HYSTERESIS, rel=0.05)


@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_every_catalog_arm_has_joint_errors_its_ik_can_invert(robot: str) -> None:
    """IK's fixed point needs each joint's error to turn slower than the joint (|de/dq| < 1)."""
    errors = typical_joint_errors(robot, np.random.default_rng(1))
    q = np.linspace(-np.pi, np.pi, 4001)[:, None] * np.ones(6)
    assert np.abs(errors.slopes(q)).max() < 0.2
    assert np.abs(errors.offsets(q)).max() < 2e-3  # far inside the file bound (MAX_AMPLITUDE per term)


@pytest.mark.parametrize("robot", ["ur5e", "ur10e", "ur5"])
def test_stops_scattered_by_standstill_sigma_repeat_to_the_datasheet_figure(robot: str) -> None:
    """An arm whose joints stop with `standstill_sigma` scatter reaches its datasheet RP (ISO 9283's
    formula, `hil.verify.accuracy`, on 30 simulated stops) on average over workspace poses: the
    scatter is what UR publishes, measured the standard's way, not by `RP_PER_SIGMA`'s algebra."""
    rng = np.random.default_rng(3)
    sigma = standstill_sigma(robot)
    kin = Kinematics(Geometry.nominal(robot, smr=(0.0, 0.0, 0.045)))
    rps = []
    for _ in range(150):
        q = rng.uniform(-np.pi, np.pi, 6)
        q[1] = rng.uniform(-np.pi, 0.0)
        stops = q + rng.normal(0.0, sigma, (30, 6))
        attained = kin.points(stops, frame="base")
        rps.append(pose_accuracy(attained, kin.points(q[None], frame="base")[0]).rp_l)
    assert np.mean(rps) == pytest.approx(POSE_REPEATABILITY[robot], rel=0.1)
    # a joint-level figure of the order the encoder-noise budget allows (hil.calibration.synthetic)
    assert 1e-5 < sigma < 1e-4


def test_every_catalog_arm_has_a_datasheet_repeatability() -> None:
    assert set(POSE_REPEATABILITY) == set(ROBOT_NAMES)
    assert abs(RP_PER_SIGMA - 3.616) < 1e-3  # Maxwell: 2√(2/π) + 3√(3 − 8/π)
