"""Where a program runs on the simulated station, and what a run the tracker could not see reports.

* The shipped examples, placed by default in front of the simulated tracker (`facing_frame`), keep the
  SMR within its acceptance angle and the beam clear of the arm along the whole path — checked on the
  simulator's own world model (no simulator process: the same visibility the simulated tracker uses).
* A run whose tracker streamed but never saw the SMR is ``incomplete`` (exit code 1, the reason named),
  not a hardware fault (exit code 3) — through the CLI with stand-in devices.
"""

from __future__ import annotations

import contextlib
import json
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from hil.arm.geometry import Geometry
from hil.calibration.model_file import truth_document
from hil.calibration.synthetic import Noise, random_truth
from hil.cli import main
from hil.moveb.path_plan import plan_program
from hil.moveb.program import load_program
from hil.moveb.run import facing_frame, program_in_frame, solve_trajectory
from hil.moveb.timing import Limits
from hil.station.config import default_config
from mocks.world import World

EXAMPLES = Path(__file__).parents[3] / "hil" / "moveb" / "examples"


def _sim_world(seed: int) -> tuple[World, np.ndarray]:
    """The simulated station's world and start pose for `seed`, drawn as `mocks.station` draws them."""
    rng = np.random.default_rng(seed)
    world = World(random_truth("ur5e", rng, ideal=True), lambda: np.zeros(6))
    return world, world.home_pose(rng)


@pytest.mark.parametrize("seed", [1, 2])  # 1: what `hil moveb run --sim` uses unless told otherwise
@pytest.mark.parametrize("example", ["square.moveb", "weld_seam.moveb"])
def test_the_examples_stay_in_sight_of_the_simulated_tracker(example: str, seed: int) -> None:
    world, home = _sim_world(seed)
    config = default_config()
    geometry = Geometry.nominal("ur5e", smr=config.smr["offset"])
    program = load_program(EXAMPLES / example)
    program = program_in_frame(program, facing_frame(program, world.truth.tracker.translation,
                                                     geometry.spec.reach))
    keep_in = (np.array(config.keep_in["min"]), np.array(config.keep_in["max"]))
    traj = solve_trajectory(plan_program(program, "G2"), geometry, Limits(), 125.0, home, keep_in=keep_in)
    for q in traj.Q[::5]:
        _, angle = world.state(q)
        assert angle < world.acceptance_deg - 3.0  # with room for the arm's kinematic errors
        assert not world.blocked_by_arm(q)


def test_facing_frame_centres_the_program_and_points_its_tool_at_the_tracker() -> None:
    program = load_program(EXAMPLES / "square.moveb")
    tracker = np.array([-2.0, 2.0, 0.5])
    placed = program_in_frame(program, facing_frame(program, tracker, 0.85))
    middle = 0.5 * (placed.positions.min(axis=0) + placed.positions.max(axis=0)) * 1e-3
    ahead = tracker[:2] / np.linalg.norm(tracker[:2])
    assert np.allclose(middle[:2], 0.5 * 0.85 * ahead, atol=0.02)
    assert middle[2] == pytest.approx(0.3, abs=0.02)
    to_tracker = tracker - placed.positions[0] * 1e-3
    assert placed.z_axes[0] @ to_tracker / np.linalg.norm(to_tracker) > np.cos(np.radians(3.0))


class _Robot:
    info = SimpleNamespace(rate_hz=125.0)

    def __init__(self, q: np.ndarray) -> None:
        self.q = q

    def read_joints(self, _samples: int) -> SimpleNamespace:
        return SimpleNamespace(q=self.q)

    def move_to(self, q: np.ndarray) -> None:
        self.q = q

    def follow(self, Q: np.ndarray, **_options: object) -> SimpleNamespace:
        start = time.monotonic()
        time.sleep(0.15)
        return SimpleNamespace(times=np.linspace(start, start + 0.15, len(Q)))


class _BlindTracker:
    """Streams on time, but never sees the SMR (it faces away, or the beam is blocked)."""

    def stream(self, rate_hz: float, *, stop: object) -> object:
        while not stop.is_set():  # type: ignore[attr-defined]
            yield SimpleNamespace(t=time.monotonic(), position=None)
            time.sleep(1.0 / rate_hz)


def test_a_tracker_that_saw_nothing_makes_the_run_incomplete_not_a_hardware_fault(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    import hil.jobs.moveb
    import hil.station.devices
    from hil.jobs.station import StationSetup

    world, home = _sim_world(1)
    truth = truth_document(world.truth, Noise())

    @contextlib.contextmanager
    def station(_source: object):  # type: ignore[no-untyped-def]
        yield StationSetup(default_config(), {}, truth)

    devices = SimpleNamespace(robot=_Robot(home), tracker=_BlindTracker(), close=lambda: None)
    monkeypatch.setattr(hil.jobs.moveb, "station_setup", station)
    monkeypatch.setattr(hil.station.devices, "open_devices", lambda _config: devices)
    monkeypatch.setattr(hil.station.devices, "ask_controller", lambda _config: devices.robot.info)
    out = tmp_path / "run.json"
    code = main(["moveb", "run", str(EXAMPLES / "square.moveb"), "--sim", "--ideal", "--out", str(out)])
    captured = capsys.readouterr()
    assert code == 1, captured.err
    doc = json.loads(captured.out)
    assert doc == json.loads(out.read_text())
    assert doc["status"] == "incomplete" and doc["exit_code"] == 1 and doc["coverage"] == 0.0
    assert "line of sight" in doc["error"] and doc["lost_samples"] > 0
    assert "hardware" not in captured.err
