"""The simulated station's configuration says what its arm's operator knows: payload, mounting and
where the SMR sits on the flange."""

from __future__ import annotations

import json
import socket

import numpy as np

from hil.arm.payload import Payload, gravity_of_mounting
from hil.calibration.model_file import truth_document
from hil.calibration.synthetic import Noise, random_truth
from hil.station.simulated import operator_knowledge, simulated_station
from mocks.station import simulated_serial


def test_the_config_carries_the_truths_payload_but_not_its_compliance() -> None:
    with simulated_station("ur5e", speed=10.0, seed=2) as (config, identity, truth, _sim):
        assert truth["compliance"] and truth["thermal"]  # a real arm, hidden
        assert config.payload == Payload.from_dict(truth["payload"])
        assert identity["robot"]["payload"] == truth["payload"]
        assert list(config.values["robot"]["mounting"]) == [0.0, 0.0, 0.0]
        assert "compliance" not in config.values["robot"]


def test_a_rigid_station_has_nothing_on_its_flange() -> None:
    with simulated_station("ur5e", speed=10.0, seed=2, rigid=True) as (config, _identity, truth, _sim):
        assert "compliance" not in truth and "payload" not in truth
        assert config.payload is None


def test_the_mounting_turns_floor_gravity_into_the_truths() -> None:
    for rpy in ((0.3, -0.2, 0.0), (np.pi, 0.0, 0.0), (0.0, 1.2, 0.0), (-0.5, 0.4, 1.0)):
        g = gravity_of_mounting(rpy)
        mounting = operator_knowledge({"gravity": g.tolist()})["robot__mounting"]
        np.testing.assert_allclose(gravity_of_mounting(mounting), g, atol=1e-12)
    assert operator_knowledge({}) == {}


def test_the_config_knows_the_smr_offset_from_its_holders_drawing() -> None:
    """Where the SMR sits on the flange is on the SMR holder's drawing: the configuration carries the
    truth's offset to the drawing's 0.5 mm (a MOVEB run without a model assumed (0, 0, 45) mm while the
    simulated SMR sat at (1.0, 36.0, 25.2) mm, and reported 9.5 mm of path error on a tilting seam)."""
    known = operator_knowledge({"smr": [0.00094573, 0.0360371, 0.02576638]})["smr__offset"]
    np.testing.assert_allclose(known, [0.001, 0.036, 0.026], atol=1e-12)
    with simulated_station("ur5e", speed=10.0, seed=2) as (config, _identity, truth, _sim):
        offset = np.array(config.values["smr"]["offset"])
        assert np.abs(offset - np.array(truth["smr"])).max() <= 0.25e-3


def _serial(sim) -> str:
    """What the simulated controller's dashboard answers to ``get serial number``."""
    with socket.create_connection((sim.address, sim.info["dashboard_port"]), timeout=10) as conn:
        stream = conn.makefile("rw", encoding="ascii", newline="\n")
        stream.readline()  # the greeting
        stream.write("get serial number\n")
        stream.flush()
        return stream.readline().strip()


def test_each_simulated_arm_is_a_robot_of_its_own_and_keeps_its_serial(tmp_path) -> None:
    """The serial is the simulated arm's: another robot type, seed or truth is another robot (two
    stations on one machine once both reported 20235500001 and refused each other), the same arm is the
    same robot (a re-run resumes its campaign, found by serial)."""
    truth = tmp_path / "truth.json"
    arm = random_truth("ur5e", np.random.default_rng(5), ideal=True)
    truth.write_text(json.dumps(truth_document(arm, Noise())))
    serials = []
    for robot, seed, truth_file in (("ur5e", 1, None), ("ur10e", 1, None), ("ur5e", 2, None),
                                    ("ur5e", 1, str(truth))):
        with simulated_station(robot, truth_file, speed=10.0, seed=seed) as (_config, _identity, _truth, sim):
            serials.append(_serial(sim))
    assert len(set(serials)) == 4, serials
    assert all(s.startswith("9999") and len(s) == 11 and s.isdigit() for s in serials), serials
    # the same arm again is the same robot: the station is started with `simulated_serial` of what makes
    # the arm (mocks.station.start_station), so the serial its controller answered is that function's
    # value now, in this process; a fifth station of the first arm (about 20 s of the suite) would ask
    # the same function again with the same arguments
    assert serials[0] == simulated_serial("ur5e", 1) and serials[3] == simulated_serial("ur5e", 1, str(truth))


def test_the_ideal_and_the_realistic_arm_of_one_seed_are_two_robots() -> None:
    """--ideal gives the arm without joint errors and lost motion, --no-ideal the realistic one: same
    geometry, another robot (its own serial), and the truth each reports says which it is."""
    seen = {}
    for ideal in (True, False):
        with simulated_station("ur5e", None, speed=10.0, seed=3, ideal=ideal) as (_c, _i, truth, sim):
            seen[ideal] = (_serial(sim), truth)
    (serial_ideal, ideal_truth), (serial_real, real_truth) = seen[True], seen[False]
    assert serial_ideal != serial_real
    assert serial_ideal == simulated_serial("ur5e", 3, ideal=True)
    assert serial_real == simulated_serial("ur5e", 3, ideal=False)
    assert "joint_errors" not in ideal_truth and "lost_motion" not in ideal_truth
    assert len(real_truth["joint_errors"]) == 6 and len(real_truth["lost_motion"]) == 6
    assert real_truth["joints"] == ideal_truth["joints"] and real_truth["tracker"] == ideal_truth["tracker"]
    assert real_truth["compliance"] == ideal_truth["compliance"]


def test_the_ideal_arm_keeps_the_serial_it_always_had() -> None:
    """A store's simulated campaigns are found by serial: the ideal arm's must not change."""
    import hashlib

    key = "ur5e|seed=1|truth=|rigid=False"
    old = f"9999{int(hashlib.sha256(key.encode()).hexdigest(), 16) % 10**7:07d}"
    assert simulated_serial("ur5e", 1, ideal=True) == old
