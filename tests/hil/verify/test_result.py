"""The figures: commanded positions in the tracker frame by the model, or by a frame fitted with the
controller's model; AP of a known offset, RP of the noise; orientation said to be not measured."""

from __future__ import annotations

import numpy as np
import pytest

from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.campaign.steps import PoseRecord
from hil.verify.cube import POSE_NAMES
from hil.verify.design import COMPENSATED, UNCOMPENSATED
from hil.verify.result import ORIENTATION, evaluate, model_frame, registered_frame, summary
from tests.hil.verify.station import cell


def records_of(design, kin: Kinematics, rng, sigma: float = 5e-6) -> dict[int, PoseRecord]:
    out = {}
    for v in design.visits():
        p = kin.points(v.q)[0] + rng.normal(0, sigma, 3)
        out[v.index] = PoseRecord(v.index, "validation", v.q, v.q, np.zeros(6), p, np.zeros(3), 3)
    return out


def test_with_the_true_model_compensated_ap_is_the_noise_and_uncompensated_the_controllers_error() -> None:
    c = cell()
    design = c.design(cycles=4)
    rng = np.random.default_rng(1)
    doc = evaluate(design, records_of(design, Kinematics(c.truth), rng), model_frame(c.truth),
                   controller=c.controller)
    comp, unc = doc["results"][COMPENSATED], doc["results"][UNCOMPENSATED]
    assert comp["AP_max"] < 2e-5 and comp["RP_max"] < 5e-5
    # the controller's own model misses by what its IK's joints put the true SMR off the cube point
    truth_base = Kinematics(c.truth)
    for row in unc["poses"]:
        i = POSE_NAMES.index(row["pose"])
        miss = truth_base.points(design.joints[UNCOMPENSATED][i], frame="base")[0] - design.positions()[i]
        assert row["AP_P"] == pytest.approx(np.linalg.norm(miss), abs=2e-5)
        assert np.allclose([row["AP_x"], row["AP_y"], row["AP_z"]], miss, atol=2e-5)  # base axes
        assert len(row["offsets"]) == 4 and row["n"] == 4
    assert unc["AP_max"] > 10 * comp["AP_max"]
    assert doc["orientation"] == ORIENTATION == "not measured: one SMR gives position only"
    assert doc["frame"]["source"] == "model" and doc["own_frame"]["frame"]["source"] == "registered"
    assert doc["own_frame"]["AP_max"] <= unc["AP_max"]  # a fitted frame takes up part of it
    assert doc["measured"] == doc["visits"] == 40 and doc["skipped"] == []
    assert "uncompensated AP" in summary(doc) and "compensated AP" in summary(doc)


def test_without_a_model_the_frame_is_fitted_with_the_controllers_model() -> None:
    c = cell(seed=4)
    design = c.design(cycles=3, modes=(UNCOMPENSATED,))
    rng = np.random.default_rng(2)
    # an arm that moves exactly by the controller's model: the fitted frame leaves only the noise
    ctrl = c.controller
    exact = Geometry(ctrl.robot, ctrl.joints, ctrl.flange, c.truth.smr, c.truth.tracker)
    records = records_of(design, Kinematics(exact), rng)
    frame = registered_frame(design, records, c.controller)
    doc = evaluate(design, records, frame)
    assert doc["frame"]["source"] == "registered" and "lower bound" in doc["frame"]["note"]
    assert list(doc["results"]) == [UNCOMPENSATED] and "own_frame" not in doc
    assert doc["results"][UNCOMPENSATED]["AP_max"] < 2e-5
