"""Snapshots of every screen at 80x24, as text, from canned state (no station, no clock, no randomness).

The app is built by the same factory as ``hil tui`` with ``start_station=False``; the canned state
goes through the same messages the session posts. ``HIL_SNAPSHOT_UPDATE=1`` rewrites the files in
``snapshots/`` (review the diff: it is the screen).
"""

from __future__ import annotations

import asyncio
import time

import numpy as np
import pytest

from hil.campaign.events import (
    PhaseChanged,
    PointMeasured,
    PoseReached,
    PoseSkipped,
    PoseStarted,
    RunStarted,
    StateChanged,
    Suspended,
)
from hil.station.config import default_config
from hil.store import CampaignRecord, CampaignSummary, ModelRecord, RobotIdentity, ValidationRecord
from hil.tui.app import create_app
from hil.tui.messages import CampaignLoaded, EngineEvent, HistoryLoaded, SelectionDone, StationChanged
from hil.tui.state import StationState
from tests.hil.tui.conftest import expect_snapshot

T0 = 1_700_000_000.0
CID = "20231114-221320-abcd"
SIZE = (80, 24)


@pytest.fixture(autouse=True)
def utc(monkeypatch):
    monkeypatch.setenv("TZ", "UTC")
    time.tzset()
    yield
    monkeypatch.undo()
    time.tzset()


def offline_app():
    app = create_app(start_station=False, sim=True, out_dir="/tmp/exports", now=lambda: T0 + 95.0)
    app.session.config = default_config().with_overrides(campaign__calibration_poses=12,
                                                          campaign__validation_poses=4,
                                                          campaign__candidates=3000)
    return app


def summary(cid: str = CID, status: str = "accepted", t: float = T0, rms: float | None = 9.6e-6):
    return CampaignSummary(id=cid, created=t, updated=t + 60, station="simulated station", robot="ur5e",
                           serial="20235500001", status=status, planned=22, measured=22, skipped=0,
                           fit_rms=3e-6 if rms else None, validation_rms=rms, passed=bool(rms))


def record() -> CampaignRecord:
    names = ["joint2.tx", "joint2.tz", "joint2.rx", "joint3.rz", "smr.x", "tracker.ty"]
    params = [{"name": n, "value": (k - 2.5) * 4e-4, "std": 1e-6 * (k + 1)} for k, n in enumerate(names)]
    doc = {"parameters": params, "fit": {"rms": 3e-6, "max": 5e-6, "poses": 18, "used": 18,
                                         "rejected": [], "condition": 20.5}}
    stats = {"before": {"count": 4, "mean": 2.1e-3, "rms": 2.19e-3, "max": 2.96e-3},
             "after": {"count": 4, "mean": 8.9e-6, "rms": 9.6e-6, "max": 1.35e-5}}
    return CampaignRecord(summary=summary(), robot=RobotIdentity("ur5e", "20235500001"),
                          config=default_config().as_dict(), config_hash="0" * 64, plan=None, detail="",
                          result={"model": doc}, software="0.1.0",  # finished: it has a report
                          models=[ModelRecord(1, T0, 3e-6, doc)],
                          validations=[ValidationRecord(1, T0, 1, stats["before"], stats["after"], True,
                                                        None)])


def run_events() -> list:
    ev = [RunStarted(campaign=CID, t=T0, robot="ur5e", station="simulated station", poses=16),
          StateChanged(campaign=CID, t=T0, state="running", previous="idle"),
          PhaseChanged(campaign=CID, t=T0 + 1, phase="measure", detail="16 of 16 poses to measure")]
    rng = np.random.default_rng(3)
    for k in range(6):
        target = rng.uniform(-2, 2, 6).round(3).tolist()
        q = (np.array(target) + 1e-4).tolist()
        p = rng.uniform(-1, 3, 3).round(4).tolist()
        t = T0 + 5 + 5 * k
        ev += [PoseStarted(campaign=CID, t=t, index=k, role="calibration", target=target),
               PoseReached(campaign=CID, t=t + 2, index=k, role="calibration", q=q, q_spread=[0] * 6,
                           seconds=2.0),
               PointMeasured(campaign=CID, t=t + 3, index=k, role="calibration", q=q, p=p,
                             p_spread=[0] * 3, samples=5, deviation=None if k < 3 else 1e-3 * (1 + k / 3),
                             target=target)]
    ev += [PoseSkipped(campaign=CID, t=T0 + 40, index=6, role="calibration", reason="beam did not return"),
           PoseStarted(campaign=CID, t=T0 + 41, index=7, role="calibration", target=[0.1] * 6),
           StateChanged(campaign=CID, t=T0 + 63, state="suspended", previous="running"),
           Suspended(campaign=CID, t=T0 + 63, kind="protective_stop",
                     message="protective stop: clear its cause and unlock it on the teach pendant; the run "
                             "resumes by itself", detail="ProtectiveStop: protective stop", timeout=600.0,
                     on_timeout="fail")]
    return ev


def test_station_screen_snapshot():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            app.session.station = StationState(
                phase="connected", name="simulated station", simulated=True, detail="speed 20x, seed 1",
                robot_address="127.0.0.2", tracker_url="socket://127.0.0.2:4000",
                robot={"model": "UR5e", "serial": "20235500001", "software": "5.15.0"},
                tracker={"name": "AT960-SIM", "serial": "960001", "firmware": "1.4.2"},
                safety="normal", lock="locked in",
                last_point="x 3015.037  y -27.310  z 385.475 mm  (spread 7.0 µm, 5 samples)")
            app.post_message(StationChanged())
            await pilot.pause()
            await expect_snapshot(pilot, "station")

    asyncio.run(scenario())


def test_plan_screen_snapshot():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("2")
            rng = np.random.default_rng(0)
            points = np.column_stack([rng.uniform(-0.8, 0.8, 12), rng.uniform(-0.8, 0.8, 12),
                                      rng.uniform(0.1, 1.0, 12)])
            report = {"index": "O1", "value": 3.683e-4, "percent_of_bound": 93.7, "method": "tabu",
                      "seconds": 0.56, "travel_time": {"ordered": 9.2}, "candidates": {"found": 3000},
                      "count": 12, "parameters": 25, "poses": []}
            app.post_message(SelectionDone(report, points, (2.5, 0.0, 0.5), True))
            await pilot.pause()
            await expect_snapshot(pilot, "plan")

    asyncio.run(scenario())


def test_run_screen_snapshot_with_a_suspension_banner():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            for event in run_events():
                app.post_message(EngineEvent(event))
            await pilot.pause()
            await pilot.press("3")
            await pilot.pause()
            assert app.screen.query_one("#banner").display
            await expect_snapshot(pilot, "run")

    asyncio.run(scenario())


def test_results_screen_snapshot():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            app.post_message(CampaignLoaded(record()))
            await pilot.pause()
            assert app.screen is app.views["results"]
            await expect_snapshot(pilot, "results")

    asyncio.run(scenario())


def test_history_screen_snapshot():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("5")
            rows = [summary(), summary("20231114-203000-beef", "interrupted", T0 - 7000, None),
                    summary("20231113-101500-0042", "rejected", T0 - 90000, 1.4e-4)]
            app.post_message(HistoryLoaded(rows, "/var/lib/hil/hil.db"))
            await pilot.pause()
            await expect_snapshot(pilot, "history")

    asyncio.run(scenario())


def test_help_screen_snapshot():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("question_mark")
            await pilot.pause()
            await expect_snapshot(pilot, "help")
            await pilot.press("escape")
            assert app.screen is app.views["station"]

    asyncio.run(scenario())
