"""What finds a verification again: its identity, apart from a calibration's and from another model's,
cube or controller; and the model's sha256, the same from a model file as from a calibrate result."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hil.arm.controller_model import ControllerCalibration
from hil.calibration.synthetic import random_truth
from hil.errors import InputError
from hil.station.config import default_config
from hil.store.hashing import measurement_hash
from hil.verify.cube import Cube
from hil.verify.inputs import ModelInput, load_model, requested_cube
from hil.verify.session import identity


def test_a_verification_is_found_by_its_model_cube_cycles_and_controller_not_as_a_calibration(tmp_path):
    base = default_config().as_dict()
    truth = random_truth("ur5e", np.random.default_rng(1), ideal=True)
    model = ModelInput.of({"format": "hil-model/1", **truth.to_dict()}, truth, "m.json")
    cube = Cube(np.array([0.5, 0.0, 0.3]), 0.2)
    nominal = ControllerCalibration()
    one = identity(base, model, cube, 30, nominal, False)
    assert one["verification"] == {"kind": "verification", "model": model.sha256, "cube": cube.to_dict(),
                                   "cycles": 30, "controller": None}
    same = measurement_hash(one)
    assert measurement_hash(identity(base, model, cube, 30, nominal, False)) == same
    assert measurement_hash(base) != same  # never a calibration's campaign
    for other in (identity(base, None, cube, 30, nominal, False),
                  identity(base, model, Cube(np.array([0.5, 0.1, 0.3]), 0.2), 30, nominal, False),
                  identity(base, model, cube, 10, nominal, False),
                  identity(base, model, cube, 30, ControllerCalibration(delta_theta=np.full(6, 1e-3)), True)):
        assert measurement_hash(other) != same
    # a calibration's own counts do not make it another verification
    counted = {**base, "campaign": {**base["campaign"], "calibration_poses": 14, "acceptance": 0.001}}
    assert measurement_hash(identity(counted, model, cube, 30, nominal, False)) == same


def test_the_verify_section_leaves_a_calibrations_identity_alone() -> None:
    """Stores written before `[verify]` existed hash their configurations without it: a calibration
    interrupted then is still found after the upgrade, and a changed cube never orphans one."""
    config = default_config().as_dict()
    before = {k: v for k, v in config.items() if k != "verify"}
    assert measurement_hash(config) == measurement_hash(before)
    moved = default_config().with_overrides(verify__centre=(0.4, 0.2, 0.3), verify__cycles=10).as_dict()
    assert measurement_hash(moved) == measurement_hash(config)


def test_the_model_hash_is_the_same_from_a_model_file_and_from_a_calibrate_result(tmp_path) -> None:
    truth = random_truth("ur5e", np.random.default_rng(2), ideal=True)
    doc = {"format": "hil-model/1", **truth.to_dict(), "fit": {"rms": 1e-5}}
    (tmp_path / "model.json").write_text(json.dumps(doc))
    (tmp_path / "result.json").write_text(json.dumps({"format": "hil-result/1", "status": "accepted",
                                                      "model": {**doc, "created": "another day"}}))
    a, b = load_model(str(tmp_path / "model.json")), load_model(str(tmp_path / "result.json"))
    assert a.sha256 == b.sha256 == ModelInput.of(doc, truth, "calibration").sha256


def test_a_station_must_name_its_cube_the_simulated_one_has_a_default() -> None:
    config = default_config()
    assert requested_cube(config, sim=True) is None
    with pytest.raises(InputError, match=r"verify.centre: .* is required on a station"):
        requested_cube(config, sim=False)
    named = config.with_overrides(verify__centre=(0.5, 0.0, 0.3))
    cube = requested_cube(named, sim=False)
    assert cube is not None and cube.edge == round(0.25 * 0.85, 3)  # a quarter of a UR5e's reach
