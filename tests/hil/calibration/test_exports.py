import numpy as np
import pinocchio as pin
import pytest
import yaml

from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.calibration.exports import export, from_ros_kinematics, to_ros_kinematics, to_urdf
from hil.calibration.identification import identify
from hil.calibration.measurements import Measurements
from hil.calibration.model_file import load_geometry, model_document, write_json
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from hil.errors import InputError


@pytest.fixture
def calibrated(rng, tmp_path):
    truth = random_truth("ur5e", rng, ideal=True)
    q, p = measure(truth, random_configurations("ur5e", 30, rng), Noise(), rng)
    fit = identify(Measurements.from_arrays(q, p, "m.csv"), "ur5e")
    doc = model_document(fit)
    path = tmp_path / "model.json"
    write_json(path, doc)
    return fit.geometry, doc, path


def test_urdf_loaded_by_pinocchio_reproduces_flange_and_smr(calibrated, rng):
    geometry, doc, _ = calibrated
    model = pin.buildModelFromXML(export(doc, geometry, "urdf"))
    data = model.createData()
    assert model.nq == 6
    tool0, smr, tracker = (model.getFrameId(n) for n in ("tool0", "smr", "tracker"))
    Q = random_configurations("ur5e", 50, rng)
    kin = Kinematics(geometry)
    flange = kin.points(Q, frame="base", point="flange")
    smr_base = kin.points(Q, frame="base")
    for q, f, s in zip(Q, flange, smr_base, strict=True):
        pin.framesForwardKinematics(model, data, q)
        assert np.abs(data.oMf[tool0].translation - f).max() < 1e-9
        assert np.abs(data.oMf[smr].translation - s).max() < 1e-9
    assert np.allclose(data.oMf[tracker].homogeneous, geometry.tracker.homogeneous, atol=1e-12)
    assert np.allclose(model.upperPositionLimit, geometry.spec.upper)


def test_ros_kinematics_yaml_round_trip(calibrated, rng):
    geometry, doc, _ = calibrated
    text = export(doc, geometry, "ros-kinematics")
    parsed = yaml.safe_load(text)["kinematics"]
    assert list(parsed) == ["shoulder", "upper_arm", "forearm", "wrist_1", "wrist_2", "wrist_3", "hash"]
    assert parsed["hash"].startswith("calib_")
    assert set(parsed["wrist_2"]) == {"x", "y", "z", "roll", "pitch", "yaw"}
    loaded = from_ros_kinematics(text, "ur5e")
    Q = random_configurations("ur5e", 50, rng)
    a = Kinematics(loaded).points(Q, frame="base", point="flange")
    b = Kinematics(geometry).points(Q, frame="base", point="flange")
    assert np.abs(a - b).max() < 1e-9


def test_nominal_yaml_matches_ur_description():
    """ur_description's ur5e default_kinematics.yaml (wrist_3 written as roll π/2, pitch π, yaw π)."""
    segs = yaml.safe_load(to_ros_kinematics(Geometry.nominal("ur5e")))["kinematics"]
    assert segs["shoulder"]["z"] == 0.1625
    assert segs["upper_arm"]["roll"] == pytest.approx(np.pi / 2)
    assert segs["forearm"]["x"] == -0.425
    assert (segs["wrist_1"]["x"], segs["wrist_1"]["z"]) == (-0.3922, 0.1333)
    assert segs["wrist_2"]["y"] == pytest.approx(-0.0997)
    assert segs["wrist_2"]["roll"] == pytest.approx(np.pi / 2)
    R = pin.rpy.rpyToMatrix(segs["wrist_3"]["roll"], segs["wrist_3"]["pitch"], segs["wrist_3"]["yaw"])
    assert np.allclose(R, pin.rpy.rpyToMatrix(np.pi / 2, np.pi, np.pi))
    assert segs["wrist_3"]["y"] == pytest.approx(0.0996)


def test_json_model_round_trip(calibrated, rng):
    geometry, doc, path = calibrated
    loaded, saved = load_geometry(path)
    Q = random_configurations("ur5e", 20, rng)
    assert np.abs(Kinematics(loaded).points(Q) - Kinematics(geometry).points(Q)).max() < 1e-12
    assert saved["format"] == "hil-model/1" and len(saved["parameters"]) == 27
    assert {"rms", "max", "iterations", "condition", "rejected", "correlated"} <= set(saved["fit"])
    assert saved["input"]["sha256"] == doc["input"]["sha256"] and saved["software"]["pinocchio"]
    assert all(p["std"] > 0 for p in saved["parameters"])


def test_a_campaign_result_is_accepted_where_a_model_is(calibrated, rng, tmp_path):
    geometry, doc, _path = calibrated
    result = tmp_path / "result.json"
    write_json(result, {"format": "hil-result/1", "status": "done", "model": doc})
    loaded, saved = load_geometry(result)
    Q = random_configurations("ur5e", 5, rng)
    assert np.abs(Kinematics(loaded).points(Q) - Kinematics(geometry).points(Q)).max() < 1e-12
    assert saved["format"] == "hil-model/1"
    write_json(result, {"format": "hil-result/1", "status": "failed", "model": None})
    with pytest.raises(InputError, match="result.json: the campaign result holds no model .status 'failed'"):
        load_geometry(result)
    with pytest.raises(InputError, match="expected hil-truth/1"):  # where only a truth will do
        load_geometry(result, ("hil-truth/1",))


def test_yaml_refuses_a_non_nominal_flange():
    g = Geometry.nominal("ur5e")
    g.flange = g.flange * pin.exp6(np.r_[1e-4, 0, 0, 0, 0, 0])
    with pytest.raises(InputError, match="flange"):
        to_ros_kinematics(g)
    assert "tool0" in to_urdf(g)


def test_missing_keys_are_named(tmp_path, calibrated):
    _, doc, _ = calibrated
    broken = dict(doc)
    del broken["tracker"]
    path = tmp_path / "broken.json"
    write_json(path, broken)
    with pytest.raises(InputError, match="broken.json: missing field 'tracker'"):
        load_geometry(path)
    broken = dict(doc, joints=doc["joints"][:5])
    write_json(path, broken)
    with pytest.raises(InputError, match="'joints' must be a list of 6"):
        load_geometry(path)
    path.write_text('{"format": "hil-model/1",\n "robot": }')
    with pytest.raises(InputError, match="broken.json: line 2: not valid JSON"):
        load_geometry(path)


def test_a_campaign_model_carries_the_hash_of_its_measurements(rng, tmp_path):
    """A campaign's poses never were a file: they are hashed as the measurements CSV they make, so the
    model, its URDF and its YAML name the data (`sha256sum` of the exported CSV gives the same)."""
    import hashlib

    from hil.calibration.measurements import write_measurements
    from hil.campaign.calibration_plan import measurements_of
    from hil.campaign.steps import PoseRecord

    truth = random_truth("ur5e", rng, ideal=True)
    q, p = measure(truth, random_configurations("ur5e", 30, rng), Noise(), rng)
    records = [PoseRecord(i + 6, "calibration", q[i], q[i], np.zeros(6), p[i], np.zeros(3), 5)
               for i in range(len(q))]
    meas = measurements_of(records, "campaign C-1")
    write_measurements(tmp_path / "m.csv", q, p)
    assert meas.sha256 == hashlib.sha256((tmp_path / "m.csv").read_bytes()).hexdigest()
    assert list(meas.lines) == [r.index for r in records]  # poses named by their campaign number

    fit = identify(meas, "ur5e")
    doc = model_document(fit)
    assert doc["input"]["sha256"] == meas.sha256
    for fmt in ("urdf", "ros-kinematics"):
        assert f"sha256 {meas.sha256}" in export(doc, fit.geometry, fmt)

    # measurements built without a digest still give a model that names its data
    bare = Measurements(q, p, np.arange(len(q)), "live", "")
    assert identify(bare, "ur5e").sha256 == meas.sha256
    # and a model that carries none (older files) says so instead of an empty hash
    doc["input"]["sha256"] = ""
    header = export(doc, fit.geometry, "urdf").splitlines()[1]
    assert "sha256 unknown" in header and not header.rstrip(" ->").endswith("sha256")
