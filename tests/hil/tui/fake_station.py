"""The terminal app's session on in-process fake devices: a real engine, store and plan, no simulator.

The arm and the tracker are the engine tests' fakes (`tests.hil.campaign.fakes`), raising the drivers'
own typed errors where the app must react to them (an emergency stop, a lost beam); the pose chooser is
a quick random one, so a whole small campaign takes a second or two.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

import numpy as np

from drivers.robot.errors import EmergencyStop, MotionAborted
from drivers.robot.model import ControllerInfo
from drivers.tracker.errors import TargetLost
from hil.calibration.synthetic import random_truth
from hil.campaign.calibration_plan import Choice
from hil.station.config import default_config
from hil.station.devices import Devices
from hil.store import Store
from hil.tui.app import create_app
from tests.hil.campaign.fakes import FakeArm, FakeTracker, visible_poses

SERIAL = "20235500001"


@dataclass
class Arm(FakeArm):
    """A fake arm; move number `hold_move` runs until `stop()`, `estop_move` hits an emergency stop."""

    hold_move: int | None = None
    estop_move: int | None = None
    info: ControllerInfo = field(
        default_factory=lambda: ControllerInfo("UR5e", SERIAL, "5.15.0", (5, 15, 0, 0), "e", 500.0))

    def __post_init__(self) -> None:
        super().__post_init__()
        self.holding = threading.Event()  # the held move is under way
        self.stopped = threading.Event()
        self.stopped_while_holding = False

    def move_to(self, q, *, speed=None, acceleration=None, samples=1):
        n = self.moves + 1
        if n == self.estop_move:
            self.moves = n
            raise EmergencyStop("emergency stop")
        if n == self.hold_move:
            self.moves = n
            self.stopped.clear()
            self.holding.set()
            if not self.stopped.wait(30.0):
                raise TimeoutError("nobody stopped the held move")
            self.stopped_while_holding = True
            raise MotionAborted("stop() was called while a motion was in progress")
        return super().move_to(q, speed=speed, acceleration=acceleration)

    def stop(self) -> None:
        super().stop()
        self.stopped.set()

    def check_status(self) -> None:
        pass

    def reconnect(self) -> ControllerInfo:
        return self.info

    def close(self) -> None:
        pass


@dataclass
class Tracker(FakeTracker):
    """A fake tracker whose beam is blocked from measurement `block_at` on, until `blocked` is cleared."""

    block_at: int | None = None
    identity: Any = field(default_factory=lambda: SimpleNamespace(name="AT960-FAKE", serial_number=960001,
                                                                  firmware=(1, 4, 2), interface="fake"))

    def __post_init__(self) -> None:
        super().__post_init__()
        self.blocked = False

    def measure_point(self, samples: int = 1):
        if self.block_at is not None and self.measurements + 1 >= self.block_at:
            self.block_at, self.blocked = None, True
        if self.blocked:
            raise TargetLost("MOT_ReadLockStatus: locked out", 0, 6021)  # as the GeoCOM driver says it
        return super().measure_point(samples)

    def relock(self) -> bool:
        return not self.blocked

    def ready(self) -> bool:
        return True

    def lock_status(self) -> str:
        return "not locked" if self.blocked else "locked in"

    def open(self):
        return self

    def close(self) -> None:
        pass


class FakeStation:
    """Truth, config, store and devices for one app; `app()` builds the app on them."""

    def __init__(self, tmp_path, monkeypatch, seed: int = 3, cal: int = 12, val: int = 4, **arm_kw: Any):
        self.rng = np.random.default_rng(seed)
        self.truth = random_truth("ur5e", self.rng, ideal=True)
        self.arm = Arm(visible_poses(self.truth, 1, self.rng)[0], **arm_kw)
        self.tracker = Tracker(self.arm, self.truth)
        self.config = default_config().with_overrides(
            campaign__calibration_poses=cal, campaign__validation_poses=val, robot__settle_time=0.0,
            smr__offset=tuple(self.truth.smr + 0.003),
            tracker__position=tuple(self.truth.tracker.translation + 0.05),
            warmup__enabled=False, drift__every=0,  # a wall-clock run whose moves the tests count:
            campaign__approach=0.0)  # one move a pose (tests/hil/campaign/test_approach.py: the approach)
        self.store = Store.open(tmp_path / "hil.db")
        self.reconnects: list[Any] = []  # what the session's connect() after a run gets
        self.asked: list[Any] = []  # the configurations the controller was asked what it is for
        rng = self.rng

        def chooser(config: Any) -> Any:
            return lambda request: Choice(visible_poses(request.model, request.count, rng), {})

        def open_devices(config: Any) -> Devices:
            outcome = self.reconnects.pop(0) if self.reconnects else self.devices()
            if isinstance(outcome, BaseException):
                raise outcome
            return outcome

        monkeypatch.setattr("hil.campaign.chooser.campaign_chooser", chooser)
        def ask_controller(config: Any) -> ControllerInfo:  # the arm's word, before the devices open
            self.asked.append(config)
            return self.arm.info

        monkeypatch.setattr("hil.station.devices.open_devices", open_devices)
        monkeypatch.setattr("hil.station.devices.ask_controller", ask_controller)

    def devices(self) -> Devices:
        return Devices(self.arm, self.tracker)  # type: ignore[arg-type]

    def app(self, **kwargs: Any):
        app = create_app(start_station=False, **kwargs)
        session = app.session
        session.config, session.identity, session.store = self.config, self.config.as_dict(), self.store
        session.devices = self.devices()
        session.station.phase = "connected"
        return app
