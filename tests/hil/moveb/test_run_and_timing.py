from __future__ import annotations

import subprocess
import sys
from itertools import pairwise
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hil.arm.geometry import Geometry
from hil.arm.ik import UnreachableError, solve_ik, solve_path
from hil.arm.kinematics import Kinematics
from hil.calibration.synthetic import random_truth
from hil.cli import main
from hil.moveb.accuracy import distance_to_path
from hil.moveb.path_plan import SAMPLES_HEADER, plan_program
from hil.moveb.program import load_program
from hil.moveb.run import path_accuracy, register, tool_targets
from hil.moveb.timing import Limits

EXAMPLES = Path(__file__).parents[3] / "hil" / "moveb" / "examples"
Q0 = np.array([0.3, -1.2, 1.5, -1.8, -1.57, 0.2])


@pytest.mark.parametrize("rate", [500.0, 125.0])
def test_feed_profile_honours_the_limits(rate: float) -> None:
    plan = plan_program(load_program(EXAMPLES / "square.moveb"), "G3")
    lim = Limits(velocity=200.0, acceleration=1500.0, jerk=15000.0, normal_acceleration=800.0)
    law, _samples = plan.timed(lim, rate)
    dt = 1.0 / rate
    assert np.allclose(np.diff(law.t), dt)
    assert law.s[0] == 0.0 and law.s[-1] == pytest.approx(plan.length)
    v = np.diff(law.s) / dt
    a = np.diff(v) / dt
    j = np.diff(a) / dt
    assert v.min() >= -1e-9 and v.max() <= lim.velocity * 1.001
    assert np.abs(a).max() <= lim.acceleration * 1.02
    assert np.abs(j).max() <= lim.jerk * 1.05
    vm = 0.5 * (v[1:] + v[:-1])
    kappa = plan.curve.evaluate(law.s[1:-1])["curvature"]
    assert (kappa * vm ** 2).max() <= lim.normal_acceleration * 1.05
    assert v[0] < lim.acceleration * dt and v[-1] < lim.acceleration * dt  # at rest at both ends


def test_ik_solves_the_calibrated_chain_and_refuses_the_unreachable() -> None:
    truth = random_truth("ur5e", np.random.default_rng(3), rigid=True)  # the geometry's IK, not the sag's
    kin = Kinematics(truth)
    target = pin.SE3(kin.flange_poses(Q0 + 0.1)[0])
    q = solve_ik(kin, target, Q0)
    assert np.allclose(kin.flange_poses(q)[0], target.homogeneous, atol=1e-9)
    far = pin.SE3(np.eye(3), np.array([3.0, 0.0, 0.5]))
    with pytest.raises(UnreachableError, match="out of reach"):
        solve_ik(kin, far, Q0)


def test_ik_answer_a_turn_away_is_brought_back_within_the_limits() -> None:
    kin = Kinematics(Geometry.nominal("ur5e"))
    q_true = np.array([0.3, -1.2, 1.5, -1.8, -1.57, 5.9])  # joint 6 near its +2π limit
    target = pin.SE3(kin.flange_poses(q_true)[0])
    seed = q_true.copy()
    seed[5] = -0.2  # the seed is a whole turn away (the same wrist pose): the turn nearest it
    q = solve_ik(kin, target, seed)
    assert np.allclose(kin.flange_poses(q)[0], target.homogeneous, atol=1e-9)
    assert q[5] == pytest.approx(5.9 - 2 * np.pi, abs=1e-6)
    seed[5] = 12.0  # past the limit: the iteration lands at 5.9 + 2π, one turn back is within
    q = solve_ik(kin, target, seed)
    assert q[5] == pytest.approx(5.9, abs=1e-6)


def test_ik_follows_a_planned_path_with_the_smr_as_tcp() -> None:
    geometry = Geometry.nominal("ur5e", smr=(0.0, 0.0, 0.045))
    kin = Kinematics(geometry)
    plan = plan_program(load_program(EXAMPLES / "square.moveb"), "G2")
    _law, s = plan.timed(Limits(velocity=400.0), 125.0)
    # anchor the program where the arm can reach: start at Q0's SMR position, tool down
    F = kin.flange_poses(Q0)[0]
    shift = (F[:3, :3] @ geometry.smr + F[:3, 3]) * 1e3 - s.position[0]
    Q = solve_path(kin, tool_targets(s.position + shift, s.z_axis, s.x_axis, geometry.smr), Q0)
    got = kin.points(Q, frame="base", point="smr") * 1e3
    assert np.abs(got - (s.position + shift)).max() < 1e-6


def test_path_accuracy_and_registration() -> None:
    path = np.c_[np.linspace(0, 100, 1001), np.zeros(1001), np.zeros(1001)]
    measured = path[::10] + np.array([0.0, 0.05, 0.0])
    acc = path_accuracy(path, measured, np.array([[50.0, 0.0, 0.0]]))
    assert acc["max_deviation_mm"] == pytest.approx(0.05)
    assert acc["rms_deviation_mm"] == pytest.approx(0.05)
    assert acc["corner_deviation_measured_mm"][0] == pytest.approx(0.05)
    L = np.c_[np.r_[np.linspace(0, 100, 501), np.full(500, 100.0)],
              np.r_[np.zeros(501), np.linspace(0.2, 100, 500)], np.zeros(1001)]
    R = pin.rpy.rpyToMatrix(0.1, -0.2, 2.0)
    in_tracker = (L[::5] - np.array([1000.0, 200.0, 0.0])) @ R  # R^T applied: base -> tracker
    back = register(in_tracker, L[::5], L)
    assert np.abs(back - L[::5]).max() < 1e-6


def _rms_to(path: np.ndarray, points: np.ndarray) -> float:
    return float(np.sqrt(np.mean(distance_to_path(points, path) ** 2)))


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), lag=st.floats(0.0, 0.4), noise=st.floats(0.001, 0.5))
def test_a_rigid_fit_is_never_worse_than_no_fit(seed: int, lag: float, noise: float) -> None:
    """Points already in the path's frame (a model's tracker pose), matched to the commanded positions
    by stamps off by `lag` of the path (a tracker clock mapped wrongly): the best rigid fit, started
    there too, is at most as far from the path as the points unfitted. The time-matched start alone
    fell into another minimum (a model's 0.064 mm reported as 'rigidly fitted max 24.9 mm')."""
    rng = np.random.default_rng(seed)
    corners = rng.uniform(-100.0, 100.0, (int(rng.integers(3, 7)), 3))
    path = np.vstack([np.linspace(a, b, max(2, int(np.linalg.norm(b - a) / 0.2)), endpoint=False)
                      for a, b in pairwise(corners)] + [corners[-1:]])
    idx = np.arange(0, len(path), 5)
    measured = path[idx] + rng.normal(0.0, noise, (len(idx), 3))
    matched = path[np.clip(idx + int(lag * len(path)), 0, len(path) - 1)]
    fitted = register(measured, matched, path, start=(np.eye(3), np.zeros(3)))
    assert _rms_to(path, fitted) <= _rms_to(path, measured) + 1e-12


def test_cli_plan_writes_samples(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "samples.csv"
    assert main(["moveb", "plan", str(EXAMPLES / "square.moveb"), "--continuity", "G3",
                 "--out", str(out)]) == 0
    lines = out.read_text().splitlines()
    assert lines[0] == ",".join(SAMPLES_HEADER)
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    assert np.all(np.diff(rows[:, 0]) > 0)
    assert np.allclose(np.linalg.norm(rows[:, 4:7], axis=1), 1.0, atol=1e-12)
    import json

    doc = json.loads(capsys.readouterr().out)
    assert doc["continuity"] == "G3" and doc["rate_hz"] == 500.0
    slow = main(["moveb", "plan", str(EXAMPLES / "square.moveb"), "--out", str(out), "--velocity", "20",
                 "--rate", "125"])
    assert slow == 0
    doc_slow = json.loads(capsys.readouterr().out)
    # at 20 mm/s the 400 mm path alone takes 20 s (at 100 mm/s the corners' curvature dominates)
    assert doc_slow["cycle_time_s"] > 20.0 > 1.5 * doc["cycle_time_s"] and doc_slow["rate_hz"] == 125.0


def test_cli_plan_bad_program_is_one_line_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.moveb"
    bad.write_text("MOVEB 0 0 0 0 0 1 1 0 0 1 1\n# c\nMOVEB 1 0 0 0 0 1 1 0 0 -1 1\n")
    assert main(["moveb", "plan", str(bad), "--out", str(tmp_path / "s.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert "bad.moveb: line 3: D (chord-height error): must be in [0.0001, 100] mm, got -1" in err
    assert len(err.splitlines()) == 1


def test_run_figure_draws_path_and_deviation() -> None:
    from hil.moveb.plot import run_figure

    plan = plan_program(load_program(EXAMPLES / "square.moveb"), "G2")
    dense = plan.dense(0.5)
    rng = np.random.default_rng(0)
    measured = dense.position[::3] + rng.normal(0, 0.01, (len(dense.position[::3]), 3))
    dev = np.linalg.norm(measured - dense.position[::3], axis=1)
    png = run_figure(dense.position, dense.s, measured, dev, plan.program.positions[1:-1], "square")
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20000


#: The fast-time factor of the end-to-end runs whose subject is the path, not the pace: the simulated
#: station keeps its own clock (a GeoCOM reading still takes 0.1 s of it, mocks.station.GEOCOM_MEASURE_S),
#: so the figures are the same and a run takes a fraction of the wall time. One run stays in real time
#: (`test_cli_run_the_tracker_saw_only_in_part_is_incomplete`, the command's default).
FAST = 10.0


def _moveb_run(tmp_path: Path, prog: Path, name: str, *extra: str, exit_code: int = 0,
               speed: float = 1.0) -> dict:
    """``hil moveb run`` of `prog` on the simulated station at `speed` (its fast-time factor): the
    result document."""
    import json
    import os

    out = tmp_path / f"{name}.json"
    root = str(Path(__file__).parents[3])
    env = dict(os.environ, PYTHONPATH=root + os.pathsep + os.environ.get("PYTHONPATH", ""))
    # run from tmp_path: relative paths (the truth) must reach the simulator's own process intact
    res = subprocess.run([sys.executable, "-m", "hil", "moveb", "run", str(prog), "--sim", "--frame",
                          "current", "--velocity", "150", "--speed", str(speed), "--out", str(out), *extra],
                         capture_output=True, text=True, timeout=240, cwd=tmp_path, env=env)
    assert res.returncode == exit_code, res.stderr
    return json.loads(out.read_text())


def test_cli_run_on_the_simulated_station_and_what_the_model_changes(tmp_path: Path) -> None:
    """The same program on the same (non-nominal) simulated arm: with the nominal model the path is
    off by the arm's kinematic errors; with the arm's true model it follows to tens of µm."""
    from hil.calibration.model_file import truth_document, write_json
    from hil.calibration.synthetic import Noise

    prog = tmp_path / "small.moveb"
    prog.write_text("MOVEB 0 0 0 0 0 1 1 0 0 0.5 0.2\nMOVEB 100 0 0 0 0 1 1 0 0 0.5 0.2\n"
                    "MOVEB 100 100 0 0 0 1 1 0 0 0.5 0.2\n")
    truth = tmp_path / "truth.json"
    # a rigid cold arm: the model's geometry is the subject (a warming, sagging arm is not the cold model)
    write_json(truth, truth_document(random_truth("ur5e", np.random.default_rng(5), rigid=True), Noise()))
    nominal = _moveb_run(tmp_path, prog, "nominal", "--truth", "truth.json", speed=FAST)
    assert nominal["registered"] is True and nominal["path_accuracy_registered"] is None
    assert nominal["status"] == "done" and nominal["coverage"] > 0.9
    assert 0.05 < nominal["path_accuracy"]["max_deviation_mm"] < 2.0
    assert max(nominal["joint_speeds"]["peak_fraction"]) <= 1.0
    model = _moveb_run(tmp_path, prog, "model", "--truth", "truth.json", "--model", "truth.json",
                       "--plot", "run.png", speed=FAST)
    assert (tmp_path / "run.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert model["registered"] is False
    acc, fitted = model["path_accuracy"], model["path_accuracy_registered"]
    assert acc["max_deviation_mm"] < 0.1 and fitted["max_deviation_mm"] < 0.1
    assert acc["rms_deviation_mm"] < 0.5 * nominal["path_accuracy"]["rms_deviation_mm"]
    assert len(acc["corner_deviation_measured_mm"]) == 1 and model["coverage"] > 0.9  # one interior point
    # a GeoCOM stream gives about 10 readings a second (mocks.station.GEOCOM_MEASURE_S), 15 mm apart at
    # 150 mm/s: the chord between the two readings around the blended corner cuts it, by up to the
    # reported resolution, and the arm strays from the commanded path by at most the path deviation
    corner, resolution = acc["corner_deviation_measured_mm"][0], acc["corner_resolution_mm"][0]
    bound = acc["corner_deviation_commanded_mm"][0] + acc["max_deviation_mm"] + resolution
    assert resolution > 0.0 and corner <= bound
    # the nominal arm measured in the true frame: its absolute error, which the fit above hid
    absolute = _moveb_run(tmp_path, prog, "absolute", "--truth", "truth.json", "--model", "truth.json",
                          "--ik", "nominal", speed=FAST)
    assert absolute["ik"] == "nominal" and absolute["registered"] is False
    assert absolute["path_accuracy"]["max_deviation_mm"] > 0.2
    assert absolute["path_accuracy"]["max_deviation_mm"] > 5 * acc["max_deviation_mm"]


def test_cli_run_the_tracker_saw_only_in_part_is_incomplete(tmp_path: Path) -> None:
    """On the default simulated arm, the square anchored at the start pose (``--frame current``) moves
    the beam onto the arm's own upper arm after its first side: the tracker loses the SMR, the figures
    cover only that side, and say so."""
    doc = _moveb_run(tmp_path, EXAMPLES / "square.moveb", "square", exit_code=1)
    assert doc["status"] == "incomplete" and doc["exit_code"] == 1
    # a GeoCOM reading takes 0.1 s of the station's time (mocks.station.GEOCOM_MEASURE_S): the stream
    # gets at most 10 a second, so the lost stretch is tens of readings
    assert doc["coverage"] < 0.5 and doc["lost_samples"] > 30
    assert "longest unmeasured stretch s = " in doc["error"]
    assert None in doc["path_accuracy"]["corner_deviation_measured_mm"]  # a corner nobody saw


def test_cli_run_through_an_emscon_tracker_measures_like_geocom(tmp_path: Path) -> None:
    """The same path measured through Leica's emScon TPI (continuous-time mode, the tracker's own
    time stamps) instead of GeoCOM: the arm's true model follows it to tens of µm, fully covered."""
    from hil.calibration.model_file import truth_document, write_json
    from hil.calibration.synthetic import Noise

    prog = tmp_path / "small.moveb"
    prog.write_text("MOVEB 0 0 0 0 0 1 1 0 0 0.5 0.2\nMOVEB 100 0 0 0 0 1 1 0 0 0.5 0.2\n"
                    "MOVEB 100 100 0 0 0 1 1 0 0 0.5 0.2\n")
    truth = tmp_path / "truth.json"
    write_json(truth, truth_document(random_truth("ur5e", np.random.default_rng(5), rigid=True), Noise()))
    doc = _moveb_run(tmp_path, prog, "emscon", "--truth", "truth.json", "--model", "truth.json",
                     "--tracker-protocol", "emscon", speed=FAST)
    assert doc["status"] == "done" and doc["coverage"] > 0.9 and doc["lost_samples"] == 0
    assert doc["path_accuracy"]["max_deviation_mm"] < 0.1
    assert doc["path_accuracy"]["samples"] > 50
    # at 100 records a second the corner is resolved to a few µm: the measured figure is the arm's own
    acc = doc["path_accuracy"]
    assert acc["corner_resolution_mm"][0] < 0.01
    bound = acc["corner_deviation_commanded_mm"][0] + acc["max_deviation_mm"] + acc["corner_resolution_mm"][0]
    assert acc["corner_deviation_measured_mm"][0] <= bound


def _example_run(tmp_path: Path, example: str, protocol: str, *extra: str) -> tuple[dict, str]:
    """``hil moveb run`` of an example on the simulated station in fast time: (result, stderr)."""
    import json
    import os

    out = tmp_path / f"{example}-{protocol}.json"
    root = str(Path(__file__).parents[3])
    env = dict(os.environ, PYTHONPATH=root + os.pathsep + os.environ.get("PYTHONPATH", ""))
    program = str(EXAMPLES / f"{example}.moveb")
    res = subprocess.run([sys.executable, "-m", "hil", "moveb", "run", program, "--sim", "--ideal",
                          "--speed", "20",
                          "--tracker-protocol", protocol, "--out", str(out), *extra],
                         capture_output=True, text=True, timeout=240, cwd=tmp_path, env=env)
    assert res.returncode == 0, res.stderr
    return json.loads(out.read_text()), res.stderr


@pytest.mark.parametrize("protocol", ["geocom", "emscon"])
def test_the_square_in_fast_time_measures_alike_on_emscon_and_geocom(tmp_path: Path, protocol: str) -> None:
    """The example square on the simulated station at --speed 20, no model: emScon's continuous-time
    stream (the tracker's own stamps) and GeoCOM's polled one give the same figures within the
    trackers' accuracy: the nominal model's path error on this arm, max about 0.45 mm, RMS about
    0.27 mm. emScon reported max 17-21 mm, RMS 7-8 mm (its stamps ran 20 times fast)."""
    doc, _ = _example_run(tmp_path, "square", protocol)
    assert doc["status"] == "done" and doc["coverage"] > 0.9 and doc["registered"] is True
    acc = doc["path_accuracy"]
    assert acc["max_deviation_mm"] < 0.7 and 0.15 < acc["rms_deviation_mm"] < 0.4


def test_the_weld_seam_assumes_the_stations_smr_offset_and_says_so(tmp_path: Path) -> None:
    """The tilting weld seam without a model, on emScon in fast time: the run assumes the simulated
    station's SMR offset (its holder's drawing), names it and its source in the result and on stderr,
    and measures the seam to GeoCOM's level; it reported 9.5 mm assuming (0, 0, 45) mm. --plot says
    what it wrote, as every output does."""
    doc, err = _example_run(tmp_path, "weld_seam", "emscon", "--plot", "seam.png")
    assert doc["status"] == "done" and doc["coverage"] > 0.9
    assert doc["path_accuracy"]["max_deviation_mm"] < 1.0
    assert "smr.offset" in doc["smr"]["source"] and len(doc["smr"]["offset_mm"]) == 3
    assert "no model: the SMR centre is assumed at (" in err
    assert "wrote seam.png (" in err and (tmp_path / "seam.png").read_bytes()[:4] == b"\x89PNG"
