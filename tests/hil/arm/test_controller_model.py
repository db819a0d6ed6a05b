"""The controller's model: nominal DH + factory deltas, as a Geometry, and its JSON block."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.arm.controller_model import ControllerCalibration
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.errors import InputError


def _dh_fk(theta, a, d, alpha, q):
    """Standard DH, written out independently: Π Rz(θ+q)·Tz(d)·Tx(a)·Rx(α)."""
    T = np.eye(4)
    for i in range(6):
        ct, st = np.cos(q[i] + theta[i]), np.sin(q[i] + theta[i])
        ca, sa = np.cos(alpha[i]), np.sin(alpha[i])
        T = T @ np.array([[ct, -st * ca, st * sa, a[i] * ct], [st, ct * ca, -ct * sa, a[i] * st],
                          [0.0, sa, ca, d[i]], [0.0, 0.0, 0.0, 1.0]])
    return T


def _random(rng: np.random.Generator) -> ControllerCalibration:
    return ControllerCalibration(rng.normal(0, 2e-3, 6), rng.normal(0, 1e-3, 6), rng.normal(0, 1e-3, 6),
                                 rng.normal(0, 2e-3, 6))


@pytest.mark.parametrize("robot", ["ur5e", "ur10e", "ur3e", "ur5"])
def test_geometry_matches_the_dh_chain(robot: str) -> None:
    rng = np.random.default_rng(4)
    cal = _random(rng)
    kin = Kinematics(cal.geometry(robot))
    theta, a, d, alpha = cal.dh(robot)
    for q in rng.uniform(-np.pi, np.pi, (20, 6)):
        np.testing.assert_allclose(kin.flange_poses(q)[0], _dh_fk(theta, a, d, alpha, q), atol=1e-12)


def test_real_calibrations_with_cancelling_d_of_hundreds_of_metres_are_accepted_and_exact() -> None:
    # the shape of a real UR5 calibration.conf (ur_modern_driver issue #108): d2/d3 cancel
    cal = ControllerCalibration.from_dict({
        "delta_theta": [0.0, -0.77, 0.78, -0.01, 0.0, 0.0], "delta_a": [0.0, 0.0003, 0.002, 0.0, 0.0, 0.0],
        "delta_d": [0.0, 232.67, -229.36, -3.31, 0.0, 0.0], "delta_alpha": [0.0, 0.001, 0.0, 0.0, 0.0, 0.0]})
    kin = Kinematics(cal.geometry("ur5"))
    theta, a, d, alpha = cal.dh("ur5")
    for q in np.random.default_rng(6).uniform(-np.pi, np.pi, (10, 6)):
        np.testing.assert_allclose(kin.flange_poses(q)[0], _dh_fk(theta, a, d, alpha, q), atol=1e-11)


def test_zero_deltas_are_the_nominal_geometry() -> None:
    q = np.random.default_rng(1).uniform(-3, 3, (10, 6))
    a = Kinematics(ControllerCalibration().geometry("ur5e")).flange_poses(q)
    b = Kinematics(Geometry.nominal("ur5e")).flange_poses(q)
    np.testing.assert_allclose(a, b, atol=1e-15)
    assert ControllerCalibration().is_zero()


def test_full_dh_round_trip_and_nominal_values() -> None:
    cal = _random(np.random.default_rng(2))
    spec = get_robot("ur10e")
    theta, a, d, alpha = cal.dh(spec)
    np.testing.assert_allclose(d - cal.delta_d, spec.dh.d)
    back = ControllerCalibration.from_dh("ur10e", theta, a, d, alpha)
    for key in ("delta_theta", "delta_a", "delta_d", "delta_alpha"):
        np.testing.assert_allclose(getattr(back, key), getattr(cal, key), atol=1e-15)


def test_json_block_round_trip_and_checksums_follow_the_deltas() -> None:
    cal = _random(np.random.default_rng(3))
    back = ControllerCalibration.from_dict(json.loads(json.dumps(cal.to_dict())))
    assert back.checksums() == cal.checksums()
    moved = ControllerCalibration(cal.delta_theta, cal.delta_a, cal.delta_d + np.r_[0, 0, 1e-6, 0, 0, 0],
                                  cal.delta_alpha)
    changed = [a != b for a, b in zip(cal.checksums(), moved.checksums(), strict=True)]
    assert changed == [False, False, True, False, False, False]


@pytest.mark.parametrize(("block", "message"), [
    ([], "expected an object"),
    ({"delta_theta": [0] * 6, "delta_a": [0] * 6, "delta_d": [0] * 6}, "missing field 'delta_alpha'"),
    ({"delta_theta": [0] * 5, "delta_a": [0] * 6, "delta_d": [0] * 6, "delta_alpha": [0] * 6},
     "'delta_theta' must be a list of 6"),
    ({"delta_theta": [0] * 6, "delta_a": [0, 0, True, 0, 0, 0], "delta_d": [0] * 6, "delta_alpha": [0] * 6},
     "delta_a[2]: expected a number, got true"),
    ({"delta_theta": [0] * 6, "delta_a": [0] * 6, "delta_d": [0, 0, 0, 4.25e5, 0, 0], "delta_alpha": [0] * 6},
     "delta_d[3]: must be in [-10000, 10000] m, got 425000"),
    ({"delta_theta": [0] * 6, "delta_a": [0] * 6, "delta_d": [0.425, 0, 0, 0, 0, 0], "delta_alpha": [0] * 6},
     "delta_d[0]: must be in [-0.1, 0.1] m, got 0.425"),
    ({"delta_theta": [0] * 6, "delta_a": [0] * 6, "delta_d": [0, 232.67, -229.36, 0, 0, 0],
      "delta_alpha": [0] * 6}, "delta_d[1] + delta_d[2] + delta_d[3] = 3.31 m"),
])
def test_bad_blocks_name_the_field(block: object, message: str) -> None:
    with pytest.raises(InputError, match="truth.json: controller") as info:
        ControllerCalibration.from_dict(block, "truth.json: controller")
    assert message in str(info.value)
