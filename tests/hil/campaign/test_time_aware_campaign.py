"""`hil calibrate --selection time-aware` on the simulated station: calibration and validation poses in one
tour from where the arm stands, method 000 reported beside, accepted, and a kill -9 mid-tour resumes it."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np

from hil.calibration.model_file import truth_document, write_json
from hil.calibration.synthetic import Noise, random_truth
from hil.store import Store

ROOT = Path(__file__).resolve().parents[3]


def cli(tmp: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "hil", "calibrate", "--sim", "--speed", "40", "--seed", "5",
            "--truth", str(tmp / "truth.json"), "--poses", "14", "--validation", "6", "--candidates", "2000",
            "--db", str(tmp / "hil.db"), "--no-warmup", "--selection", "time-aware",
            "--search-time", "2", *extra]


def write_truth(tmp: Path) -> None:
    # the rigid arm: the subject is the selection and the tour, not the compliance
    write_json(tmp / "truth.json", truth_document(random_truth("ur5e", np.random.default_rng(5), rigid=True),
                                                  Noise()))


def test_a_time_aware_campaign_tours_both_roles_and_is_accepted(tmp_path):
    write_truth(tmp_path)
    out = tmp_path / "result.json"
    proc = subprocess.run(cli(tmp_path, "--json", "--out", str(out)), cwd=ROOT, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    events = [json.loads(line) for line in proc.stdout.splitlines()]
    (plan,) = [e for e in events if e["event"] == "PlanReady"]
    roles = [p["role"] for p in plan["poses"]]
    assert roles.count("validation") == 6
    # one tour: the validation poses are not all at its end
    assert roles[-6:] != ["validation"] * 6
    sel = plan["selection"]["calibration"]
    assert sel["method"] == "time-aware" and sel["form"] == "target"
    assert roles.count("calibration") == sel["predicted"]["poses"] >= 10
    # method 000's 14 poses reported beside, and the tour is predicted faster at no less accuracy
    assert sel["seed_method"]["count"] == 14
    assert sel["predicted"]["robot_time"] < sel["seed_method"]["robot_time"]
    assert sel["predicted"]["relative_error"] <= 1.0 + 1e-9
    measured = [e for e in events if e["event"] == "PointMeasured"]
    assert [e["index"] for e in measured if e["role"] != "bootstrap"] == [p["index"] for p in plan["poses"]]
    result = json.loads(out.read_text())
    assert result["status"] == "accepted"


def test_kill_9_mid_tour_then_resume_visits_the_same_tour(tmp_path):
    write_truth(tmp_path)
    proc = subprocess.Popen(cli(tmp_path, "--json"), cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True, start_new_session=True)
    plan = None
    seen = 0
    try:
        for line in proc.stdout:
            event = json.loads(line)
            if event["event"] == "PlanReady":
                plan = event
            if event["event"] == "PointMeasured" and event["role"] != "bootstrap":
                seen += 1
                if seen == 8:
                    os.killpg(proc.pid, signal.SIGKILL)
                    break
    finally:
        proc.wait(timeout=30)
    assert plan is not None and proc.returncode == -signal.SIGKILL
    again = subprocess.run(cli(tmp_path, "--json", "--resume"), cwd=ROOT, capture_output=True, text=True,
                           timeout=300)
    assert again.returncode == 0, again.stderr[-2000:]
    with Store.open(tmp_path / "hil.db") as store:
        (summary,) = store.campaigns()
        planned = store.poses(summary.id)
    # the stored tour is the one visited: same indices, roles and targets as the first run planned
    assert [(p.index, p.role) for p in planned if p.role != "bootstrap"] == \
        [(p["index"], p["role"]) for p in plan["poses"]]
