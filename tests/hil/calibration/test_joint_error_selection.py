"""Joint errors in the fit: recovery to their σ, the cross-validated choice, lost motion, the model file."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hil.arm.blas_threads import limit_blas_threads
from hil.arm.joint_errors import JointErrors
from hil.arm.kinematics import Kinematics
from hil.calibration.identification import identify
from hil.calibration.joint_error_request import JointErrorRequest, parse_request
from hil.calibration.joint_error_selection import identify_with_joint_errors
from hil.calibration.measurements import Measurements
from hil.calibration.model_file import load_geometry, model_document, write_json
from hil.calibration.synthetic import Noise, random_configurations, random_truth
from hil.errors import InputError

limit_blas_threads()


def _station(seed: int, poses: int, terms=None, lost=None, two_sided: bool = False):
    rng = np.random.default_rng(seed)
    truth = random_truth("ur5e", rng, rigid=True)
    if terms is not None:
        truth.joint_errors = JointErrors.of(terms)
    truth.lost_motion = None if lost is None else np.asarray(lost, float)
    q = random_configurations("ur5e", poses, rng)
    d = rng.choice([-1.0, 1.0], q.shape) if two_sided else np.ones_like(q)
    p = Kinematics(truth).points(q, directions=d) + rng.normal(0, Noise(20e-6).tracker_sigma, (poses, 3))
    meas = Measurements.from_arrays(q + rng.normal(0, Noise().encoder_sigma, q.shape), p,
                                    directions=d if two_sided else None)
    return truth, meas


def _truth_error(truth, model, seed: int = 99) -> float:
    q = random_configurations("ur5e", 200, np.random.default_rng(seed))
    d = Kinematics(model).points(q) - Kinematics(truth).points(q)
    return float(np.sqrt(np.mean(np.sum(d * d, axis=1))))


@pytest.mark.parametrize(("text", "expected"), [
    ("none", JointErrorRequest("none")), ("AUTO", JointErrorRequest("auto")),
    ("2,1", JointErrorRequest("orders", (1, 2))), ("1,lost", JointErrorRequest("orders", (1,), True)),
])
def test_parse_request(text, expected):
    assert parse_request(text) == expected
    assert parse_request(str(expected)) == expected


@pytest.mark.parametrize("text", ["0", "4", "1,x", "", "lots"])
def test_parse_request_refuses(text):
    with pytest.raises(InputError, match="--joint-errors"):
        parse_request(text)


def test_fixed_orders_recover_known_terms_within_their_standard_deviation():
    rng = np.random.default_rng(21)
    terms = [[[k, *rng.normal(0.0, s, 2)] for k, s in ((1, 50e-6), (2, 30e-6))] for _ in range(6)]
    _, meas = _station(3, 120, terms)
    fit = identify_with_joint_errors(meas, "ur5e", request=JointErrorRequest("orders", (1, 2)))
    z = []
    for name, v, s in zip(fit.names, fit.values, fit.std, strict=True):
        if ".cos" in name or ".sin" in name:
            joint, term = name.split(".")
            true = terms[int(joint[5:]) - 1][int(term[3:]) - 1][1 if term.startswith("cos") else 2]
            z.append((v - true) / s)
    assert len(z) == 24
    assert np.max(np.abs(z)) < 3.5  # each within ~3σ
    assert 0.5 < np.sqrt(np.mean(np.square(z))) < 1.6  # and the σ are honest, neither inflated nor too small


def test_cross_validation_keeps_nothing_on_an_arm_without_joint_errors():
    _, meas = _station(0, 40)
    fit = identify_with_joint_errors(meas, "ur5e")
    assert fit.joint_error_choice.groups == ()
    assert not fit.with_joint_errors and fit.geometry.joint_errors is None
    assert fit.joint_error_choice.steps and not fit.joint_error_choice.steps[0].kept


def test_cross_validation_keeps_the_true_terms_and_predicts_better():
    terms = [[], [[1, 2e-4, -1e-4]], [], [[2, 1.5e-4, 1e-4]], [], []]
    truth, meas = _station(1, 60, terms)
    fit = identify_with_joint_errors(meas, "ur5e")
    choice = fit.joint_error_choice
    assert set(choice.groups) == {"joint2.k1", "joint4.k2"}
    assert choice.cv_rms < 0.7 * choice.cv_rms_without
    plain = identify(meas, "ur5e")
    assert _truth_error(truth, fit.geometry) < 0.5 * _truth_error(truth, plain.geometry)


def test_lost_motion_is_estimated_when_poses_are_approached_from_both_sides():
    lost = [0.0, 1.5e-4, 0.0, 0.0, 0.0, 0.0]
    _, meas = _station(2, 60, lost=lost, two_sided=True)
    fit = identify_with_joint_errors(meas, "ur5e")
    assert "lost_motion.j2" in fit.joint_error_choice.groups
    k = fit.names.index("lost_motion.j2")
    assert abs(fit.values[k] - 1.5e-4) < 3 * fit.std[k]
    # one-sided, the same arm offers no lost motion at all: it is the joint's offset
    _, one_sided = _station(2, 60, lost=lost)
    assert not any(g.startswith("lost_motion") for g in
                   identify_with_joint_errors(one_sided, "ur5e").joint_error_choice.candidates)


def test_the_model_file_carries_the_identified_blocks(tmp_path):
    terms = [[], [[1, 2e-4, -1e-4]], [], [], [], []]
    _, meas = _station(1, 50, terms, lost=[0, 1e-4, 0, 0, 0, 0], two_sided=True)
    fit = identify_with_joint_errors(meas, "ur5e", request=JointErrorRequest("orders", (1,), True))
    path = tmp_path / "model.json"
    write_json(path, model_document(fit))
    doc = json.loads(path.read_text())
    assert len(doc["joint_errors"]) == 6 and len(doc["lost_motion"]) == 6
    assert "joint2.cos1" in [p["name"] for p in doc["parameters"]]
    assert doc["joint_error_selection"]["request"] == "1,lost"
    loaded, _ = load_geometry(path)
    assert loaded.joint_errors == fit.geometry.joint_errors
    assert np.array_equal(loaded.lost_motion, fit.geometry.lost_motion)
    q = random_configurations("ur5e", 5, np.random.default_rng(4))
    assert np.allclose(Kinematics(loaded).points(q), Kinematics(fit.geometry).points(q), atol=1e-12)


def test_validation_uses_the_directions_of_the_data():
    from hil.calibration.identification import validate

    _, meas = _station(2, 40, lost=[0, 2e-4, 0, 0, 0, 0], two_sided=True)
    fit = identify_with_joint_errors(meas, "ur5e", request=JointErrorRequest("orders", (), True))
    without = Measurements(meas.q, meas.p, meas.lines, meas.source, meas.sha256, None)
    assert validate(fit.geometry, meas).rms < validate(fit.geometry, without).rms
