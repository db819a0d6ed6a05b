"""The simulated station's arm warms up: the real ur_rtde client reads its joints getting warmer."""

from __future__ import annotations

import time

import numpy as np
import pytest
import rtde_receive

from hil.arm.thermal import Thermal
from hil.calibration.synthetic import ENCODER_SIGMA
from mocks.heating import IDLE_HEAT
from mocks.station import joint_temperatures, start_station
from mocks.ur.arm import AMBIENT_TEMPERATURE


def test_an_arm_that_stands_still_warms_only_by_holding_itself() -> None:
    """The joints heat by working (`mocks.heating`): a quarter of an hour standing powered warms them by
    at most the holding share of a moving arm's warm-up (before this, the simulator warmed an idle arm
    as fast as a moving one)."""
    sim = start_station(speed=10.0, seed=3, ideal=True)
    try:
        truth = sim.info["services"][0]["truth"]
        thermal = Thermal.from_dict(truth["thermal"])
        r = rtde_receive.RTDEReceiveInterface(sim.address)
        try:
            t0 = sim.state()["time"]
            before = np.array(r.getJointTemperatures())
            sim.inject("set_speed", speed=1000.0)  # 1 real second: over a quarter of an hour of running
            time.sleep(1.0)
            sim.inject("set_speed", speed=10.0)
            time.sleep(0.05)
            after = np.array(r.getJointTemperatures())
            t1 = sim.state()["time"]
        finally:
            r.disconnect()
    finally:
        sim.stop()
    assert t1 - t0 > 600.0
    assert np.all(before >= AMBIENT_TEMPERATURE)
    assert np.all(before <= AMBIENT_TEMPERATURE + IDLE_HEAT * thermal.rise_at(t0) + 1e-9)
    # holding, it warms (a little) ...
    assert np.all(after > before + 0.5 * IDLE_HEAT * thermal.rise_at(600.0))
    # ... and never more than the holding share of a moving arm's warm-up over the same time
    assert np.all(after <= AMBIENT_TEMPERATURE + IDLE_HEAT * thermal.rise_at(t1) + 1e-9)
    assert np.all(after < AMBIENT_TEMPERATURE + 0.5 * thermal.rise_at(t1))


def test_a_rigid_arm_and_a_cold_one_report_the_ambient_temperature() -> None:
    assert joint_temperatures(None)(3600.0) == [AMBIENT_TEMPERATURE] * 6
    warm = joint_temperatures(Thermal(rise=6.0, time_constant=900.0))
    assert warm(0.0) == [AMBIENT_TEMPERATURE] * 6
    assert warm(1e6) == pytest.approx([AMBIENT_TEMPERATURE + 6.0] * 6)


def test_a_truth_files_encoder_noise_drives_the_controllers(tmp_path) -> None:
    """``noise.encoder_sigma`` of a truth file is the spread of the controller's ``actual_q``."""
    from hil.calibration.model_file import truth_document, write_json
    from hil.calibration.synthetic import Noise, random_truth

    path = tmp_path / "truth.json"
    arm = random_truth("ur5e", np.random.default_rng(3), ideal=True)
    write_json(path, truth_document(arm, Noise(20e-6, 1e-4)))
    sim = start_station(truth=str(path), speed=10.0, seed=3)
    try:
        r = rtde_receive.RTDEReceiveInterface(sim.address)
        try:
            q = []
            for _ in range(200):
                q.append(r.getActualQ())
                time.sleep(0.004)
        finally:
            r.disconnect()
        true_q = np.array(sim.state()["q"])
    finally:
        sim.stop()
    spread = np.std(np.array(q) - true_q, axis=0)
    assert np.all(spread > 0.7e-4) and np.all(spread < 1.4e-4)  # 1e-4 rad, not the default
    assert ENCODER_SIGMA < 0.1e-4
