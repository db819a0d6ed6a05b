"""Issue 14: the controller's own model exported as UR's ur_calibration makes ur_description's YAML.

The YAML read back the way ur_description builds the arm (`from_ros_kinematics`: URDF origins, nominal
tool0) must put the flange exactly where the controller's own model does (`ControllerCalibration.
geometry`); its links must sit where the arm is, not hundreds of metres away; its ``hash`` must be the
one UR's client library computes (reference values from a g++ build of ``std::hash`` and of
``KinematicsInfo::toHash``'s stream); and what the YAML cannot hold is said, never dropped silently.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

from hil.arm.catalog import get_robot
from hil.arm.controller_model import ControllerCalibration
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.calibration.controller_export import (
    controller_ros_kinematics,
    flange_not_held,
    std_hash,
    ur_calibration_hash,
)
from hil.calibration.exports import from_ros_kinematics, to_ros_kinematics
from hil.calibration.identification import identify
from hil.calibration.measurements import Measurements
from hil.calibration.model_file import model_document, write_json
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from hil.cli import main

# UR's own example of a real UR10e's KinematicsInfo (ur_calibration's doc/algorithm.rst): the d of
# joints 2 to 4 cancel over hundreds of metres
UR10E_DH = {
    "theta": [-2.4147806894359e-07, 1.60233952386695, -1.68607190752171, 0.0837331147700119,
              -1.01260355871158e-07, 3.91986209186124e-08],
    "a": [2.12234865571206e-05, 0.0193171326277006, -0.569251663611088, -4.61409023720934e-05,
          -6.39280053471802e-05, 0.0],
    "d": [0.180539811714259, 439.140974079901, -446.027059806332, 7.0603368964236, 0.119811341150314,
          0.115670917257426],
    "alpha": [1.57014608044242, 0.0013941666682559, 0.00693818880325995, 1.56998468543761,
              -1.57038520649543, 0.0],
}
ROS_LINKS = ("shoulder", "upper_arm", "forearm", "wrist_1", "wrist_2", "wrist_3")


def _random_calibration(rng: np.random.Generator, spread: float = 0.3) -> ControllerCalibration:
    """Deltas like a factory calibration's: milliradians, tenths of millimetres, and cancelling d
    values of up to `spread` metres on the parallel joints 2 to 4; the flange's a and α untouched."""
    d23 = rng.uniform(-spread, spread)
    d34 = rng.uniform(-spread, spread)
    delta_d = rng.normal(scale=2e-4, size=6) + np.array([0.0, d23, -d23 + d34, -d34, 0.0, 0.0])
    delta_a, delta_alpha = rng.normal(scale=2e-4, size=6), rng.normal(scale=1e-3, size=6)
    delta_a[5] = delta_alpha[5] = 0.0
    return ControllerCalibration(rng.normal(scale=1e-3, size=6), delta_a, delta_d, delta_alpha)


def _flanges(geometry: Geometry, q: np.ndarray) -> np.ndarray:
    return Kinematics(geometry).flange_poses(q)


def _assert_same_flange(text: str, calibration: ControllerCalibration, robot: str,
                        rng: np.random.Generator) -> None:
    loaded = from_ros_kinematics(text, robot)
    q = rng.uniform(-2 * np.pi, 2 * np.pi, size=(200, 6))
    ours, theirs = _flanges(loaded, q), _flanges(calibration.geometry(robot), q)
    assert np.abs(ours[:, :3, 3] - theirs[:, :3, 3]).max() < 1e-9  # metres
    assert np.abs(ours[:, :3, :3] - theirs[:, :3, :3]).max() < 1e-9  # the flange's axes too


@pytest.mark.parametrize("robot", ["ur3e", "ur5e", "ur10e", "ur16e", "ur20", "ur30", "ur5"])
def test_the_yaml_read_back_gives_the_controllers_own_flange(robot, rng):
    for _ in range(5):
        calibration = _random_calibration(rng)
        text = controller_ros_kinematics(calibration, robot)
        _assert_same_flange(text, calibration, robot, rng)
        parsed = yaml.safe_load(text)["kinematics"]
        assert list(parsed) == ["shoulder", "upper_arm", "forearm", "wrist_1", "wrist_2", "wrist_3", "hash"]


def test_urs_real_example_is_brought_back_onto_the_arm(rng):
    """The 439 m d values vanish: upper arm and forearm have no d, their links the arm's lengths."""
    calibration = ControllerCalibration.from_dh("ur10e", *(UR10E_DH[k] for k in ("theta", "a", "d", "alpha")))
    text = controller_ros_kinematics(calibration, "ur10e")
    _assert_same_flange(text, calibration, "ur10e", rng)
    segs = yaml.safe_load(text)["kinematics"]
    dh = get_robot("ur10e").dh
    assert segs["upper_arm"]["z"] == 0.0 and segs["forearm"]["z"] == 0.0
    assert abs(segs["forearm"]["x"] - dh.a[1]) < 2e-3  # -0.6127 m nominal
    assert abs(segs["wrist_1"]["x"] - dh.a[2]) < 2e-3 and abs(segs["wrist_1"]["z"] - dh.d[3]) < 2e-3
    assert max(abs(v) for s in ROS_LINKS for v in (segs[s]["x"], segs[s]["y"], segs[s]["z"])) < 1.0
    assert segs["hash"] == "calib_8779175261365510310"  # g++: KinematicsInfo::toHash of these values


def test_std_hash_is_libstdcxx():
    """Reference values printed by ``std::hash<std::string>`` of a g++ 64-bit build."""
    assert [std_hash(s) for s in (b"", b"a", b"abcdefgh", b"abcdefghi", b"-0")] == [
        6142509188972423790, 4993892634952068459, 8664279048047335611, 13036955925923793583,
        8606537264674692726]
    assert ur_calibration_hash(UR10E_DH["theta"], UR10E_DH["a"], UR10E_DH["d"], UR10E_DH["alpha"]) == \
        "calib_8779175261365510310"


def test_no_deltas_give_the_nominal_yaml():
    nominal = yaml.safe_load(to_ros_kinematics(Geometry.nominal("ur5e")))["kinematics"]
    ours = yaml.safe_load(controller_ros_kinematics(ControllerCalibration(), "ur5e"))["kinematics"]
    for name in ROS_LINKS:
        for key in ("x", "y", "z", "roll", "pitch", "yaw"):
            assert ours[name][key] == pytest.approx(nominal[name][key], abs=1e-12), (name, key)


def test_a_flange_delta_the_yaml_cannot_hold_is_said_in_the_header(rng):
    calibration = _random_calibration(rng)
    assert flange_not_held(calibration) is None
    assert "NOT HELD" not in controller_ros_kinematics(calibration, "ur5e")
    held = ControllerCalibration(calibration.delta_theta, np.r_[calibration.delta_a[:5], 3e-4],
                                 calibration.delta_d, np.r_[calibration.delta_alpha[:5], -2e-3])
    text = controller_ros_kinematics(held, "ur5e")
    header = [line for line in text.splitlines() if line.startswith("#")]
    assert any("NOT HELD" in line and "delta_a[5] = 0.0003 m" in line and "delta_alpha[5] = -0.002 rad"
               in line for line in header)
    _assert_same_flange(text, calibration, "ur5e", rng)  # everything else is the controller's


# --- hil export --which controller ------------------------------------------------------------------
@pytest.fixture(scope="module")
def fit():
    rng = np.random.default_rng(5)
    truth = random_truth("ur5e", rng, ideal=True)
    q, p = measure(truth, random_configurations("ur5e", 30, rng), Noise(), rng)
    return identify(Measurements.from_arrays(q, p, "m.csv"), "ur5e")


def _model(path, fit, calibration: ControllerCalibration | None) -> str:
    record = None if calibration is None else {**calibration.to_dict(), "checksum": [1] * 6,
                                               "calibration_status": 1}
    write_json(path, model_document(fit, controller=record))
    return str(path)


def test_hil_export_which_controller(fit, tmp_path, capsys, rng):
    calibration = _random_calibration(rng)
    model = _model(tmp_path / "model.json", fit, calibration)
    out = tmp_path / "controller.yaml"
    assert main(["export", "--model", model, "--format", "ros-kinematics", "--which", "controller",
                 "--out", str(out)]) == 0
    text = out.read_text()
    _assert_same_flange(text, calibration, "ur5e", rng)
    assert "warning" not in capsys.readouterr().err
    hil_out = tmp_path / "hil.yaml"  # the default stays hil's model, unchanged
    assert main(["export", "--model", model, "--format", "ros-kinematics", "--out", str(hil_out)]) == 0
    assert hil_out.read_text() == _hil_yaml(model)


def _hil_yaml(model: str) -> str:
    from hil.calibration.exports import export
    from hil.calibration.model_file import load_geometry

    geometry, doc = load_geometry(model)
    return export(doc, geometry, "ros-kinematics", source=model)


def test_hil_export_which_controller_warns_of_what_it_cannot_hold(fit, tmp_path, capsys):
    held = ControllerCalibration(delta_a=[0, 0, 0, 0, 0, 1e-4])
    model = _model(tmp_path / "model.json", fit, held)
    out = tmp_path / "controller.yaml"
    assert main(["export", "--model", model, "--format", "ros-kinematics", "--which", "controller",
                 "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "hil: warning: NOT HELD" in err and "delta_a[5] = 0.0001 m" in out.read_text()


@pytest.mark.parametrize(("which_format", "message"), [
    ("urdf", "--which controller: only --format ros-kinematics, not 'urdf'"),
    ("ros-kinematics", "no field 'controller'"),
])
def test_hil_export_which_controller_bad_input(fit, tmp_path, capsys, which_format, message):
    with_block = which_format != "ros-kinematics"
    model = _model(tmp_path / "model.json", fit, ControllerCalibration() if with_block else None)
    out = tmp_path / "controller.yaml"
    code = main(["export", "--model", model, "--format", which_format, "--which", "controller",
                 "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and message in err and len(err.splitlines()) == 1 and not out.exists()
    assert json.loads((tmp_path / "model.json").read_text())["format"] == "hil-model/1"
