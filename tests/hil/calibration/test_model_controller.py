"""Issue 14: a model keeps the controller's own model its campaign ran with (the ``controller`` block)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hil.arm.controller_model import ControllerCalibration
from hil.calibration.identification import identify
from hil.calibration.measurements import Measurements
from hil.calibration.model_file import model_controller, model_document, read_json, write_json
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from hil.errors import InputError

DELTAS = {"delta_theta": [1e-4, -2e-4, 3e-4, 0.0, 5e-5, -1e-4], "delta_a": [0.0, 2e-4, -1e-4, 0.0, 0.0, 0.0],
          "delta_d": [1e-4, 0.25, -0.2501, -0.0499, 2e-5, 0.0],
          "delta_alpha": [1e-4, 0.0, 5e-4, -2e-4, 1e-4, 0.0]}
# a campaign's record (`controller_record`): the KinematicsInfo fields too, which the block leaves out
RECORD = {"checksum": [11, 22, 33, 44, 55, 66], "dh_theta": [0.0] * 6, "dh_a": [0.0] * 6,
          "dh_d": [0.0] * 6, "dh_alpha": [0.0] * 6, "calibration_status": 1, **DELTAS}


@pytest.fixture(scope="module")
def fit():
    rng = np.random.default_rng(14)
    truth = random_truth("ur5e", rng, ideal=True)
    q, p = measure(truth, random_configurations("ur5e", 30, rng), Noise(), rng)
    return identify(Measurements.from_arrays(q, p, "m.csv"), "ur5e")


def test_the_controller_block_round_trips_through_the_model_file(fit, tmp_path):
    path = tmp_path / "model.json"
    write_json(path, model_document(fit, {"rms": 2e-5}, controller=RECORD))
    doc = read_json(path)
    assert doc["controller"] == {**DELTAS, "checksum": [11, 22, 33, 44, 55, 66], "calibration_status": 1}
    back = model_controller(doc, str(path))
    assert isinstance(back, ControllerCalibration)
    for key, values in DELTAS.items():
        assert getattr(back, key).tolist() == values  # bit-exact through JSON


def test_a_model_without_a_controller_block_has_none(fit):
    doc = json.loads(json.dumps(model_document(fit)))
    assert "controller" not in doc and model_controller(doc) is None


@pytest.mark.parametrize(("block", "message"), [
    ({**DELTAS, "delta_a": [0.0] * 5}, r"m\.json: controller: field 'delta_a' must be a list of 6 numbers"),
    ({k: v for k, v in DELTAS.items() if k != "delta_d"}, r"m\.json: controller: missing field 'delta_d'"),
    ({**DELTAS, "delta_theta": [True] + [0.0] * 5}, r"m\.json: controller: delta_theta\[0\]"),
    ("deltas", r"m\.json: controller: expected an object"),
])
def test_a_malformed_controller_block_names_the_file_and_the_field(block, message):
    with pytest.raises(InputError, match=message):
        model_controller({"controller": block}, "m.json")
