"""`select_timed` (hil select --method time-aware, campaign.selection = "time-aware"): the report, the two
forms, method 000 beside it, and the station's constraints on every chosen pose and leg."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hil.calibration.selection import SelectionModel, parse_constraints
from hil.calibration.timed_selection import select_timed
from hil.errors import InputError
from selector.candidates import CONSTRAINT_NAMES, evaluate
from selector.motion_time import Dwell, MotionProfile

ROOT = Path(__file__).resolve().parents[3]
TRACKER = (2.0, 0.3, 0.4)
START = [0.0, -1.6, 1.4, -1.4, -1.5, 0.0]


@pytest.fixture(scope="module")
def constraints():
    return parse_constraints(tracker=TRACKER, half_angle_deg=25.0, keep_in_lower=(-0.9, -0.9, 0.05),
                             keep_in_upper=(0.9, 0.9, 1.1), floor=0.05, joint_lower=(-np.pi,) * 6,
                             joint_upper=(np.pi, 0.0, np.pi, np.pi, np.pi, np.pi))


@pytest.fixture(scope="module")
def target_report(constraints):
    fixed = np.array([[0.3, -1.2, 1.2, -1.6, -1.5, 0.2], [-0.4, -1.9, 1.7, -1.3, -1.6, 0.5]])
    return select_timed("ur5e", 20, speed=0.5, acceleration=1.0, dwell=Dwell(0.0, 0.5, 0.05),
                        fixed=fixed, start=START, candidates=1500, seed=2, constraints=constraints,
                        compliance=True, time_limit=1.0), fixed


def test_the_target_form_matches_method_000_in_less_robot_time(target_report):
    report, fixed = target_report
    assert report["method"] == "time-aware" and report["form"] == "target"
    pred, seed = report["predicted"], report["seed_method"]
    assert seed["method"] == "tabu" and seed["count"] == 20 and seed["relative_error"] == 1.0
    assert pred["relative_error"] <= 1.0 + 1e-9
    assert pred["robot_time"] < seed["robot_time"]
    # the figures are the tour's own: recomputed from the poses and the tour
    profile = MotionProfile(0.5, 1.0, tuple(report["motion"]["max_joint_speed"]))
    poses = np.array(report["poses"])
    tour = np.array([poses[s["index"]] if s["role"] == "selected" else fixed[s["index"]]
                     for s in report["tour"]])
    assert len(tour) == len(poses) + 2 == pred["poses"] + pred["fixed_poses"]
    assert pred["move_time"] == pytest.approx(profile.tour_time(tour, np.array(START)))
    assert pred["robot_time"] == pytest.approx(pred["move_time"] + 0.55 * len(tour))
    assert report["count"] == len(poses) and len(report["parameter_names"]) == report["parameters"]


def test_every_pose_meets_every_constraint_and_legs_are_counted(target_report, constraints):
    report, _ = target_report
    model = SelectionModel("ur5e", report["smr"], TRACKER)
    passes, _ = evaluate(model, np.array(report["poses"]), constraints)
    for name in CONSTRAINT_NAMES:
        assert np.all(passes[name]), name
    assert report["predicted"]["legs_needing_detour"] >= 0
    assert report["constraints"] == constraints.as_dict()


def test_the_budget_form_fits_its_budget_and_a_too_small_one_is_refused(constraints):
    report = select_timed("ur5e", 20, speed=0.5, acceleration=1.0, budget=90.0, start=START,
                          candidates=1500, seed=3, constraints=constraints, time_limit=0.5)
    assert report["form"] == "budget" and report["predicted"]["robot_time"] <= 90.0
    assert report["count"] >= 10
    with pytest.raises(InputError, match="budget of 5 s"):
        select_timed("ur5e", 20, speed=0.5, acceleration=1.0, budget=5.0, start=START, candidates=1500,
                     seed=3, constraints=constraints, time_limit=0.2)


def test_a_budget_below_the_fewest_poses_dwell_is_refused_before_drawing(constraints, monkeypatch):
    """10 poses of 0.85 s dwell cannot fit 5 s whatever the moves: refused before the candidates are drawn
    and searched (seconds of work, found only after them before)."""
    import hil.calibration.selection as selection

    def drawn(*_args, **_kwargs):
        raise AssertionError("candidates were drawn for a budget that cannot fit")

    monkeypatch.setattr(selection, "generate_candidates", drawn)
    with pytest.raises(InputError, match=r"budget of 5 s fits fewer than the 10 poses.*8\.5 s"):
        select_timed("ur5e", 20, speed=0.5, acceleration=1.0, budget=5.0, start=START, candidates=1500,
                     seed=3, constraints=constraints, time_limit=0.2)


def test_the_cli_writes_the_time_aware_report(tmp_path):
    out = tmp_path / "poses.json"
    proc = subprocess.run([sys.executable, "-m", "hil", "select", "--robot", "ur5e", "--count", "15",
                           "--method", "time-aware", "--tracker", "2,0.3,0.4", "--candidates", "1200",
                           "--time-limit", "0.5", "--speed", "1.0", "--acceleration", "2.0", "--quiet",
                           "--out", str(out)], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    report = json.loads(out.read_text())
    # the contract of docs/design.md, Contracts: pose selection
    for key in ("robot", "index", "value", "bound", "method", "seconds", "poses"):
        assert key in report
    assert report["motion"]["speed"] == 1.0 and report["motion"]["acceleration"] == 2.0
    assert len(report["poses"]) == report["count"] and all(len(q) == 6 for q in report["poses"])
