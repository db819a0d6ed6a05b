"""The warm-up and drift watch on the simulated station: the real ur_rtde and GeoCOM clients, a simulated
arm that grows as it warms up (its truth's thermal block), in fast time.

The simulator's clock runs 200 times faster than the wall clock, so the hour a warm-up may take is
18 s at most; the engine's `PacedClock(200)` counts the station's own seconds (and the host's computing
between steps at the wall's rate, as on a real station).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np

from hil.arm.geometry import Geometry
from hil.campaign.chooser import campaign_chooser
from hil.campaign.events import (
    EventBus,
    PointMeasured,
    ReferenceMeasured,
    RunFinished,
    WarmupFinished,
    WarmupProgress,
)
from hil.campaign.runner import run_campaign
from hil.station.config import default_config
from hil.station.devices import open_devices
from hil.station.paced_clock import PacedClock, simulator_pace
from hil.store import Store

SPEED = 200.0


def test_a_simulated_campaign_warms_the_arm_up_and_watches_the_reference(tmp_path):
    from mocks.station import start_station

    sim = start_station(speed=SPEED, seed=4, ideal=True)
    try:
        svc = sim.info["services"][0]
        truth = Geometry.from_dict(svc["truth"])
        assert truth.thermal is not None  # the simulated arm warms up
        config = default_config().with_overrides(
            robot__address=sim.address, tracker__url=svc["tracker_url"], robot__speed=1.0,
            robot__acceleration=2.0, campaign__calibration_poses=14, campaign__validation_poses=4,
            campaign__candidates=2000, tracker__position=tuple(truth.tracker.translation + 0.05),
            drift__every=5, warmup__max_time=900.0,  # that it runs is shown; when it ends: test_warmup.py
            # at 200x each GeoCOM reading's host time is simulated time the arm stands holding itself
            # (a quarter of a moving arm's heat, mocks.heating): 20 readings a reference visit on a
            # loaded machine held the warming arm long enough to cool it by thousandths of a kelvin
            drift__samples=5)
        store = Store.open(tmp_path / "hil.db", synchronous="NORMAL")
        campaign = store.create_campaign(config, "ur5e")
        events: list = []
        bus = EventBus()
        bus.subscribe(store.as_subscriber(), critical=True)
        bus.subscribe(events.append)
        outcome = run_campaign(config, campaign_chooser(config), bus=bus, campaign=campaign,
                               devices=open_devices(config), clock=PacedClock(SPEED, simulator_pace(sim)))
    finally:
        sim.stop()
    assert outcome.status in ("accepted", "rejected"), outcome.error
    (done,) = [e for e in events if isinstance(e, WarmupFinished)]
    refs = [e for e in events if isinstance(e, ReferenceMeasured)]
    warm = [e for e in refs if e.phase == "warmup"]
    assert done.references == len(warm) >= 4 and len([e for e in events if isinstance(e, WarmupProgress)])
    # the warm-up came before the first point, and took the station's time, not the wall clock's
    first_point = next(i for i, e in enumerate(events) if isinstance(e, PointMeasured))
    assert events.index(done) < first_point
    assert done.seconds >= 3 * config.warmup["interval"]
    # the joint temperatures, read through ur_rtde's getJointTemperatures, rise while the warm-up cycles
    # the arm (measuring, it stands still more and may cool by hundredths of a kelvin: mocks.heating)
    temps = np.array([e.temperatures for e in refs])
    cycled = np.array([e.temperatures for e in warm])
    assert temps.shape == (len(refs), 6) and np.all(np.diff(cycled[:, 0]) >= 0) and temps[-1, 0] > temps[0, 0]
    assert np.all(np.diff([e.elapsed for e in refs]) > 0)
    # the drift watch measured the reference while measuring; none of it is a campaign point
    assert [e for e in refs if e.phase == "drift"]
    assert {m.role for m in store.measurements(campaign)} <= {"calibration", "validation"}
    stored = store.events(campaign, types=("ReferenceMeasured",))
    assert [e.seq for e in stored] == [e.seq for e in refs]  # committed, as measurements are
    block = outcome.result.drift
    assert block["warmup"]["ran"] and len(block["series"]) == len(refs)
    (finished,) = [e for e in events if isinstance(e, RunFinished)]
    assert ("drift flagged" in finished.detail) == block["flagged"]


def test_kill_9_during_the_warm_up_keeps_its_reference_measurements_and_the_rerun_continues(tmp_path):
    """``hil calibrate --sim`` killed (-9) once the warm-up has compared two reference measurements:
    they are in the store; the same command again resumes the campaign, warms up again and finishes,
    the first run's measurements kept in the result."""
    root = Path(__file__).resolve().parents[3]
    db = tmp_path / "hil.db"
    command = [sys.executable, "-m", "hil", "calibrate", "--sim", "--ideal",
               "--speed", str(SPEED), "--seed", "6",
               "--poses", "12", "--validation", "4", "--candidates", "1000", "--db", str(db), "--json",
               "--out", str(tmp_path / "r.json")]
    env = {**os.environ, "PYTHONPATH": str(root)}
    proc = subprocess.Popen(command, cwd=root, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True, env=env)
    try:
        assert proc.stdout is not None
        seen: list[dict] = []
        while not (seen and seen[-1]["event"] == "WarmupProgress"):
            line = proc.stdout.readline()
            assert line, f"hil calibrate ended before its warm-up: {seen[-3:]}"
            seen.append(json.loads(line))
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    before = [e for e in seen if e["event"] == "ReferenceMeasured"]
    assert len(before) >= 2
    with Store.open(db) as store:
        (campaign,) = store.campaigns()
        kept = store.events(campaign.id, types=("ReferenceMeasured",))
    assert [e.seq for e in kept][:len(before)] == [e["seq"] for e in before]
    done = subprocess.run(command, cwd=root, stdin=subprocess.DEVNULL, capture_output=True, text=True,
                          env=env, timeout=600)
    assert done.returncode in (0, 1), done.stderr[-2000:]
    result = json.loads((tmp_path / "r.json").read_text())
    series = result["drift"]["series"]
    assert {s["run"] for s in series} == {1, 2}
    assert [s["seq"] for s in series if s["run"] == 1][:len(before)] == [e["seq"] for e in before]
    assert result["drift"]["warmup"]["ran"]
