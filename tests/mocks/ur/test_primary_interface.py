"""The simulated controller's own kinematic model: served on 30001/30002, used for everything it computes."""

from __future__ import annotations

import contextlib
import json
import socket
import struct
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import rtde_control
import rtde_receive

from drivers.robot.kinematics_info import (
    KinematicsInfo,
    PrimaryMessage,
    PrimaryStream,
    find_kinematics_info,
    parse_version,
    read_kinematics_info,
    sub_packages,
)
from hil.arm.controller_model import ControllerCalibration
from hil.calibration.model_file import truth_controller, truth_document, write_json
from hil.calibration.synthetic import Noise, random_truth
from hil.errors import InputError
from mocks.station import station_service
from mocks.ur.controller import SimConfig, SimController
from mocks.ur.hil_model import controller_fk, nominal_fk
from mocks.ur.kin import matrix_to_pose, pose_to_matrix
from mocks.ur.process import SimProcess
from mocks.ur.testing import random_loopback, start_sim

Q_A = [0.2, -1.3, 1.3, -1.5, -1.5, 0.3]
CAL = ControllerCalibration(delta_theta=[1e-3, -2e-3, 1.5e-3, 0.0, 5e-4, -1e-3],
                            delta_a=[1e-4, 2e-3, -1e-3, 3e-4, 0.0, 1e-4],
                            delta_d=[5e-4, 0.12, -0.1, -0.02, 2e-4, 1e-4],
                            delta_alpha=[2e-3, 1e-3, -1e-3, 5e-4, -2e-3, 0.0])


def in_process(**kw: object) -> SimController:
    """A controller in this process on free ports (only raw sockets talk to it: no ur_rtde here)."""
    cfg = SimConfig(address=random_loopback(), rtde_port=0, dashboard_port=0, script_port=0, primary_port=0,
                    secondary_port=0, control_port=None, **kw)  # type: ignore[arg-type]
    return SimController(cfg).start()


@pytest.fixture
def controller() -> Iterator[SimController]:
    c = in_process(controller=CAL.to_dict())
    try:
        yield c
    finally:
        c.stop()


def read_messages(host: str, port: int, count: int, timeout: float = 5.0) -> list[PrimaryMessage]:
    """The first `count` messages a client of (host, port) receives."""
    stream, out = PrimaryStream(), []
    deadline = time.monotonic() + timeout
    with socket.create_connection((host, port), timeout=timeout) as s:
        while len(out) < count:
            s.settimeout(max(deadline - time.monotonic(), 0.01))
            chunk = s.recv(4096)
            assert chunk, "the controller closed the link"
            out.extend(stream.feed(chunk))
    return out[:count]


def expected_info(cal: ControllerCalibration, robot: str = "ur5e") -> KinematicsInfo:
    theta, a, d, alpha = cal.dh(robot)
    return KinematicsInfo(tuple(cal.checksums()), tuple(theta), tuple(a), tuple(d), tuple(alpha), 0)


# ------------------------------------------------------------------ the bytes on 30001 / 30002
@pytest.mark.parametrize("which", ["primary", "secondary"])
def test_a_version_message_then_robot_state_with_the_controllers_calibration(
        controller: SimController, which: str) -> None:
    port = getattr(controller, which).port
    messages = read_messages(controller.config.address, port, 3)
    version = parse_version(messages[0])
    assert version is not None and (version.project, version.major, version.minor) == ("URControl", 5, 15)
    assert [m.type for m in messages[1:]] == [16, 16]
    subs = {s.type: s.payload for s in sub_packages(messages[1])}
    assert sorted(subs) == [0, 1, 4, 5]
    assert len(subs[0]) == 42  # e-series RobotModeData: 47 bytes with its header (URSim 5.8)
    assert len(subs[1]) == 6 * 41 and len(subs[4]) == 12 * 8
    assert find_kinematics_info(messages) == expected_info(CAL)


def test_joint_data_and_cartesian_info_are_the_arms_state(controller: SimController) -> None:
    controller.inject("set_joints", q=Q_A)
    time.sleep(0.05)
    messages = read_messages(controller.config.address, controller.primary.port, 2)
    subs = {s.type: s.payload for s in sub_packages(messages[1])}
    q = np.array([struct.unpack_from(">3d4fB", subs[1], 41 * j)[0] for j in range(6)])
    assert np.allclose(q, Q_A, atol=1e-4)  # encoder noise only
    tcp = np.array(struct.unpack_from(">12d", subs[4])[:6])
    assert np.allclose(tcp, matrix_to_pose(controller_fk("ur5e", CAL)(q)), atol=1e-9)


def test_a_cb3_controller_sends_the_shorter_robot_mode_data() -> None:
    c = in_process(robot="ur5")
    try:
        messages = read_messages(c.config.address, c.primary.port, 2)
    finally:
        c.stop()
    assert parse_version(messages[0]).major == 3  # type: ignore[union-attr]
    subs = {s.type: s.payload for s in sub_packages(messages[1])}
    assert len(subs[0]) == 41  # 46 bytes with its header: no reserved byte before e-series
    info = find_kinematics_info(messages)
    assert info == expected_info(c.calibration, "ur5")


def test_set_calibration_swaps_the_model_and_what_is_served(controller: SimController) -> None:
    host, port = controller.config.address, controller.primary.port
    other = ControllerCalibration(delta_d=[1e-3, 0, 0, 0, 0, 0])
    controller.set_calibration(other)
    assert read_kinematics_info(host, port, timeout=5.0) == expected_info(other)
    snap = controller.arm.snapshot
    q = np.array(snap["actual_q"])
    assert np.allclose(snap["actual_TCP_pose"], matrix_to_pose(controller_fk("ur5e", other)(q)), atol=1e-12)
    assert controller.state()["controller"] == other.to_dict()


def test_clients_that_come_and_go_do_not_disturb_the_servers(controller: SimController) -> None:
    host = controller.config.address
    ticks = controller.tick_count
    for _ in range(20):
        for port in (controller.primary.port, controller.secondary.port):
            s = socket.create_connection((host, port), timeout=2.0)
            s.close()
    half = socket.create_connection((host, controller.primary.port), timeout=2.0)
    half.shutdown(socket.SHUT_WR)  # a client that says nothing and reads nothing more
    assert read_kinematics_info(host, controller.secondary.port, timeout=5.0) == expected_info(CAL)
    assert read_kinematics_info(host, controller.primary.port, timeout=5.0) == expected_info(CAL)
    half.close()
    assert controller.tick_count > ticks  # the controller kept ticking
    deadline = time.monotonic() + 5.0
    while controller.primary.connection_count() + controller.secondary.connection_count():
        assert time.monotonic() < deadline, "connections left behind"
        time.sleep(0.05)


def test_stall_stops_the_state_and_drop_connection_closes_the_link(controller: SimController) -> None:
    host, port = controller.config.address, controller.primary.port
    controller.inject("stall", on=True)
    with socket.create_connection((host, port), timeout=1.0) as s:
        stream = PrimaryStream()
        got: list[PrimaryMessage] = []
        deadline = time.monotonic() + 10.0  # the version message comes first, however loaded the machine
        while not got:
            assert time.monotonic() < deadline, "no version message"
            s.settimeout(0.1)
            with contextlib.suppress(TimeoutError):
                got.extend(stream.feed(s.recv(4096)))
        deadline = time.monotonic() + 0.5  # ... then nothing: 5 state messages' time (10 Hz)
        while time.monotonic() < deadline:
            s.settimeout(0.1)
            with contextlib.suppress(TimeoutError):
                got.extend(stream.feed(s.recv(4096)))
        assert [m.type for m in got] == [20]  # the version message only
        controller.inject("stall", on=False)
        controller.inject("drop_connection", stop_program=False)
        s.settimeout(2.0)
        data = b""
        while True:
            chunk = s.recv(65536)
            if not chunk:
                break
            data += chunk
    assert controller.primary.connection_count() == 0


def test_a_bad_controller_block_is_refused_naming_the_field() -> None:
    bad = CAL.to_dict()
    bad["delta_a"] = bad["delta_a"][:5]
    with pytest.raises(InputError, match="SimConfig.controller: field 'delta_a' must be a list of 6"):
        SimController(SimConfig(controller=bad))


def test_without_a_block_the_calibration_is_drawn_per_robot_from_the_seed() -> None:
    a = SimController(SimConfig(seed=3)).calibration
    assert a.to_dict() == SimController(SimConfig(seed=3)).calibration.to_dict()
    assert a.to_dict() != SimController(SimConfig(seed=4)).calibration.to_dict()
    assert not a.is_zero()


# ------------------------------------------------------------------ through the real ur_rtde client
@pytest.fixture(scope="module")
def rtde_sim() -> Iterator[SimProcess]:
    s = start_sim(SimConfig(speed=5.0, controller=CAL.to_dict()))
    try:
        yield s
    finally:
        s.stop()


def test_actual_tcp_pose_fk_and_ik_use_the_controllers_model(rtde_sim: SimProcess) -> None:
    assert rtde_sim.info["controller"] == CAL.to_dict()
    fk, nominal = controller_fk("ur5e", CAL), nominal_fk("ur5e")
    r = rtde_receive.RTDEReceiveInterface(rtde_sim.address)
    c = rtde_control.RTDEControlInterface(rtde_sim.address)
    try:
        assert c.moveJ(Q_A, 1.0, 2.0)
        time.sleep(0.05)
        for _ in range(50):  # joints and pose of one controller cycle (encoder noise differs per cycle)
            t0 = r.getTimestamp()
            q, pose = np.array(r.getActualQ()), np.array(r.getActualTCPPose())
            if r.getTimestamp() == t0:
                break
        assert np.allclose(pose, matrix_to_pose(fk(q)), atol=1e-9)
        assert np.linalg.norm(pose[:3] - nominal(q)[:3, 3]) > 1e-3  # not the nominal arm
        tcp = [0.0, 0.0, 0.05, 0.0, 0.0, 0.0]
        expected = matrix_to_pose(fk(np.array(Q_A)) @ pose_to_matrix(np.array(tcp)))
        assert np.allclose(c.getForwardKinematics(Q_A, tcp), expected, atol=1e-9)
        target = fk(np.array(Q_A) + 0.05)
        q_ik = np.array(c.getInverseKinematics(list(matrix_to_pose(target)), Q_A))
        assert np.allclose(fk(q_ik), target, atol=1e-8)
        assert np.allclose(q_ik, np.array(Q_A) + 0.05, atol=1e-6)
        assert np.linalg.norm(nominal(q_ik)[:3, 3] - target[:3, 3]) > 1e-3
    finally:
        c.stopScript()
        c.disconnect()
        r.disconnect()


def test_read_kinematics_info_against_the_running_simulator(rtde_sim: SimProcess) -> None:
    assert rtde_sim.info["primary_port"] == 30001 and rtde_sim.info["secondary_port"] == 30002
    info = read_kinematics_info(rtde_sim.address, rtde_sim.info["primary_port"], timeout=5.0)
    assert info == expected_info(CAL)
    back = ControllerCalibration.from_dh("ur5e", *info.dh())
    for key in ("delta_theta", "delta_a", "delta_d", "delta_alpha"):
        assert np.allclose(getattr(back, key), getattr(CAL, key), atol=1e-12)


# ------------------------------------------------------------------ the station's truth block
def test_a_truths_controller_block_is_the_controllers_model_and_is_reported(tmp_path: Path) -> None:
    truth = random_truth("ur5e", np.random.default_rng(5), ideal=True)
    path = tmp_path / "truth.json"
    write_json(path, truth_document(truth, Noise(), CAL))
    assert truth_controller(json.loads(path.read_text()), str(path)).to_dict() == CAL.to_dict()  # type: ignore[union-attr]
    c = in_process()
    try:
        service = station_service(c, truth=str(path), seed=5)
        assert c.calibration.to_dict() == CAL.to_dict()
        assert service.truth_doc["controller"] == CAL.to_dict()
        assert read_kinematics_info(c.config.address, c.primary.port, timeout=5.0) == expected_info(CAL)
    finally:
        c.stop()


def test_without_a_block_the_station_fits_one_to_its_truth_and_reports_it() -> None:
    c = in_process(seed=7)
    bare = c.calibration
    try:
        service = station_service(c, seed=7)
        block = service.truth_doc["controller"]
        assert block == c.calibration.to_dict() and block != bare.to_dict()
        assert ControllerCalibration.from_dict(block).to_dict() == block  # within the file's limits
        assert read_kinematics_info(c.config.address, c.secondary.port, timeout=5.0) == expected_info(
            c.calibration)
    finally:
        c.stop()


def test_a_malformed_truth_block_names_the_file_and_field(tmp_path: Path) -> None:
    doc = truth_document(random_truth("ur5e", np.random.default_rng(1), ideal=True), Noise())
    doc["controller"] = {**CAL.to_dict(), "delta_d": [0, 0, "x", 0, 0, 0]}
    path = tmp_path / "truth.json"
    write_json(path, doc)
    c = in_process()
    try:
        with pytest.raises(InputError, match=r"truth.json: controller: delta_d\[2\]"):
            station_service(c, truth=str(path))
    finally:
        c.stop()
