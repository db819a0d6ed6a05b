"""The engine checks planned moves against the keep-in box with the controller's own model when the
controller reported one (its driver checks with the controller's kinematics), else the nominal arm."""

from __future__ import annotations

import numpy as np

from hil.arm.catalog import get_robot
from hil.arm.controller_model import ControllerCalibration
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.campaign.runner import keep_in_model

SMR = (0.001, 0.036, 0.026)


def test_without_a_controller_model_the_nominal_arm() -> None:
    spec = get_robot("ur10e")
    q = np.random.default_rng(1).uniform(-2, 2, (5, 6))
    expected = Kinematics(Geometry.nominal(spec, SMR)).points(q, frame="base")
    assert np.allclose(Kinematics(keep_in_model(spec, SMR, None)).points(q, frame="base"), expected)


def test_with_one_its_arm_and_the_smr() -> None:
    spec = get_robot("ur10e")
    deltas = ControllerCalibration(delta_d=np.array([0.002, 0, 0, 0.001, 0, 0]),
                                   delta_theta=np.array([0, 0.001, -0.001, 0, 0, 0]))
    record = {key: getattr(deltas, key).tolist() for key in ("delta_theta", "delta_a", "delta_d",
                                                             "delta_alpha")}
    q = np.random.default_rng(2).uniform(-2, 2, (5, 6))
    theirs = Kinematics(deltas.geometry(spec, SMR)).points(q, frame="base")
    nominal = Kinematics(Geometry.nominal(spec, SMR)).points(q, frame="base")
    checked = Kinematics(keep_in_model(spec, SMR, record)).points(q, frame="base")
    assert np.allclose(checked, theirs, atol=1e-12)
    assert np.abs(checked - nominal).max() > 1e-3  # the deltas' millimetres, not the nominal arm
