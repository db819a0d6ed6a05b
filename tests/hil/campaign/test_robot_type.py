"""A campaign whose configured robot type the controller contradicts is refused before any motion.

Issue 19: ``robot.type = "ur10e"`` against a UR5e controller was accepted and saved a model labelled
ur10e; with ``ur3e`` the planner's keep-in check used the wrong arm. After connect and before anything
moves, the runner compares the controller's model with the configuration: exit 2, one line naming both,
the devices closed, the arm where it was, the run recorded as failed, no model stored.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from hil.calibration.synthetic import random_truth
from hil.campaign.calibration_plan import Choice
from hil.campaign.events import EventBus, RunFinished
from hil.campaign.runner import run_campaign
from hil.cli import main
from hil.errors import InputError
from hil.station.config import default_config
from tests.hil.campaign.fakes import FakeArm, FakeTracker, visible_poses


class _Devices:
    def __init__(self, arm: FakeArm, tracker: FakeTracker) -> None:
        self.robot, self.tracker, self.closed = arm, tracker, 0

    def close(self) -> None:
        self.closed += 1


def test_the_runner_refuses_before_any_motion_with_fake_devices() -> None:
    rng = np.random.default_rng(2)
    truth = random_truth("ur5e", rng, ideal=True)
    arm = FakeArm(visible_poses(truth, 1, rng)[0])
    arm.info = SimpleNamespace(model="UR5e", serial="20235500042", software_version="5.15")
    devices = _Devices(arm, FakeTracker(arm, truth))
    events: list = []
    bus = EventBus()
    bus.subscribe(events.append)
    config = default_config().with_overrides(robot__type="ur3e", robot__address="127.0.0.7")

    def choose(request):  # never reached: the run stops before planning
        return Choice(visible_poses(request.model, request.count, rng), {"method": "test"})

    with pytest.raises(InputError) as exc:
        run_campaign(config, choose, bus=bus, campaign="c1", devices=devices)
    assert str(exc.value) == "robot.type is ur3e but the controller at 127.0.0.7 reports UR5e"
    assert arm.moves == 0 and devices.closed == 1
    finished = [e for e in events if isinstance(e, RunFinished)]
    assert [(e.status, e.detail) for e in finished] == [("failed", str(exc.value))]


@pytest.fixture(scope="module")
def ur5e_station():
    """A simulated UR5e controller and tracker (their own process), shared by the cases below."""
    from mocks.station import start_station

    sim = start_station(robot="ur5e", speed=20.0, seed=3, ideal=True)
    yield sim
    sim.stop()


@pytest.mark.parametrize("configured", ["ur10e", "ur3e"])
def test_calibrate_refuses_a_robot_type_the_controller_contradicts(
        ur5e_station, configured: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    sim = ur5e_station
    monkeypatch.chdir(tmp_path)
    Path("station.toml").write_text(f'[robot]\ntype = "{configured}"\naddress = "{sim.address}"\n'
                                    f'[tracker]\nurl = "{sim.info["services"][0]["tracker_url"]}"\n')
    before = sim.state()
    code = main(["calibrate", "--config", "station.toml", "--db", "k.db", "--out", "r.json"])
    err = capsys.readouterr().err
    assert code == 2, err
    message = f"robot.type is {configured} in station.toml but the controller at {sim.address} reports UR5e"
    assert f"hil: error: {message}\n" in err and "Traceback" not in err
    after = sim.state()
    assert after["q"] == before["q"] and not after["moving"]  # nothing moved
    assert not Path("r.json").exists()
    # the CLI checks the controller before it creates the store: a refused station leaves no file
    # (the runner's own check, for the TUI, records a failed run: see the fake-device test above)
    assert not Path("k.db").exists()
