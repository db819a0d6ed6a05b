"""Robot time of whole campaigns on the simulated station: the time-aware stop-and-go campaign against
sweep campaigns, the same arm, in one run.

Run from the repository root: ``PYTHONPATH=. python bench/sweep_campaign.py`` (``--robots``,
``--seeds``, ``--sweep-speeds``, ``--speed``). Where bench/sweep_time.py plans and fits offline, this
runs `hil.campaign.runner.run_campaign` itself against the protocol simulators (the real ur_rtde
client, emScon over TCP), so what it times is what hil does today, bootstrap and all.

Each station (seed) is the simulator's realistic arm (joint errors, lost motion, compliance, the
SMR's payload; no thermal growth, so no warm-up, the same for both modes) with emScon. The campaigns:

* **stop-and-go**: `campaign.selection = "time-aware"` for `--poses` (method 000's accuracy of that
  many poses, in the least robot time), `campaign.validation_clusters = 4` (the configuration of the
  time-aware campaign's 135 s figure), ``robot.settle = "stable"``, the station's default movej
  (0.5 rad/s, 1 rad/s²) and ``campaign.samples`` = 5;
* **sweep** at each ``--sweep-speeds`` tool speed: ``campaign.mode = "sweep"`` through a time-aware
  choice for `--sweep-poses` poses (bench/sweep_time.py: fewer waypoints cost less time at the same
  held-out error), its bootstrap swept and resting at the validation poses inside its tour, each of
  those read off the hold of its segment (`hil.campaign.sweep_rests`; "held" in the table), a pose
  whose hold was not still visited with `--sweep-samples` readings ("still").

Both validate on 20 still poses drawn alike (the same rule and seed). **Robot time** is what the station
did, by its own accounts: the controller's joint moves (``motion_seconds``: movej, routes, approach
legs), emScon's stationary measuring (``emscon_measuring_seconds``, its lMeasTime per measurement), 10
RTDE frames per still pose (the driver's joint reading), and the sweep's segments at their planned
duration (`SweepSegmentDone.planned`: a real station follows the path as planned; the simulator in fast
time follows it `--speed` times slower, an artefact of its servo loop keeping the wall's period, so its
own clock would overstate it; `--sweep-sim-speed 1` runs the sweeps on a station of the same seed, the
same arm, at the wall's pace, where the servo loop's period is the controller's). **Accuracy**: the
campaign's validation RMS, and the truth error of its model on `--held-out` poses no campaign visits
(the station's candidates, a draw of its own, approached from below). Compute (selection, fits) is the
cell's wall time, not robot time.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from hil.arm.blas_threads import limit_blas_threads
from hil.arm.kinematics import Kinematics
from hil.calibration.model_file import load_truth, write_json
from hil.calibration.selection import design_space
from hil.calibration.synthetic import true_points
from hil.campaign.chooser import campaign_chooser
from hil.campaign.engine import RealClock
from hil.campaign.events import (
    EventBus,
    PointMeasured,
    PoseStarted,
    SweepFitted,
    SweepPlanned,
    SweepSegmentDone,
)
from hil.campaign.runner import run_campaign
from hil.errors import HilError
from hil.station.config import default_config
from hil.station.devices import open_devices
from mocks.station import start_station
from selector.candidates import Constraints

#: e-Series RTDE at 500 Hz: the driver's joint reading at a still pose is 10 frames (robot.joint_samples).
RTDE_PERIOD = 0.002
#: Seed offset of the held-out poses' candidate draw: none a campaign's selection draws with.
UNSEEN = 7919


def config_for(sim: Any, robot: str, **over: Any) -> Any:
    svc = sim.info["services"][0]
    base = dict(robot__type=robot, robot__address=sim.address, tracker__protocol="emscon",
                tracker__url=svc["tracker_emscon_url"], warmup__enabled=False, drift__every=0,
                robot__settle="stable", campaign__selection="time-aware", campaign__validation_poses=20,
                campaign__validation_clusters=4, campaign__candidates=5000, campaign__search_time=5.0)
    return default_config().with_overrides(**(base | over))


def held_out_poses(robot: str, truth: Any, count: int, seed: int) -> np.ndarray:
    constraints = Constraints(tracker=tuple(map(float, truth.tracker.translation)))
    _, cands, _ = design_space(robot, 30, candidates=max(3 * count, 3000), seed=UNSEEN + seed,
                               smr=tuple(map(float, truth.smr)), constraints=constraints,
                               scaling="expected", compliance=True, payload=truth.payload, gravity=None,
                               say=lambda *_: None)
    pick = np.random.default_rng(UNSEEN + seed).permutation(len(cands.q))[:count]
    return cands.q[pick]


def truth_rms(truth: Any, geometry: Any, q: np.ndarray) -> float:
    up = np.ones((len(q), 6))
    e = Kinematics(geometry).points(q, directions=up) - true_points(truth, q, directions=up)
    return float(np.sqrt(np.mean(np.sum(e**2, axis=1))))


def run(sim: Any, config: Any, speed: float, truth: Any, held: np.ndarray) -> dict[str, Any]:
    """One campaign on the station: its robot time by the station's accounts, and its accuracy."""
    events: list[Any] = []
    bus = EventBus()
    bus.subscribe(events.append)
    before = sim.state()
    t0 = time.perf_counter()
    out = run_campaign(config, campaign_chooser(config), bus=bus, campaign=f"c{time.monotonic_ns()}",
                       clock=RealClock(speed), devices=open_devices(config))
    wall = time.perf_counter() - t0
    after = sim.state()
    if out.result is None:
        raise RuntimeError(f"the campaign ended {out.status}: {out.error}")
    # the poses visited still (the engine's visits start with PoseStarted); the others were read off
    # the holds of the sweep's streams (`hil.campaign.sweep_rests`), which take no joint reading
    visited = {(e.role, e.index) for e in events if isinstance(e, PoseStarted)}
    still = [e for e in events if isinstance(e, PointMeasured) and (e.role, e.index) in visited]
    from_holds = [e for e in events if isinstance(e, PointMeasured) and (e.role, e.index) not in visited]
    planned = [e for e in events if isinstance(e, SweepPlanned)]
    # each segment recorded at its planned duration (the tour's and a swept bootstrap's alike)
    seconds = {e.segment: float(e.planned) for e in events if isinstance(e, SweepSegmentDone)}
    swept = set(seconds)
    moves = after["motion_seconds"] - before["motion_seconds"]
    sb, sa = before["services"], after["services"]
    measuring = sa["emscon_measuring_seconds"] - sb["emscon_measuring_seconds"]
    joints = len(still) * int(config.robot["joint_samples"]) * RTDE_PERIOD
    sweep = sum(seconds[i] for i in swept)
    fitted = [e for e in events if isinstance(e, SweepFitted)]
    r = out.result
    return {"robot_time": moves + measuring + joints + sweep, "moves": moves, "measuring": measuring,
            "sweep": sweep, "still": len(still), "held": len(from_holds), "segments": len(swept),
            "status": out.status,
            "validation_rms": r.after.rms, "truth_rms": truth_rms(truth, r.fit.geometry, held),
            "used": fitted[-1].used if fitted else None, "wall": wall,
            "rests": len(planned[-1].rests) if planned else 0}


def ratio(row: dict[str, Any], base: dict[str, Any] | None, key: str) -> str:
    """`row`'s `key` against this station's stop-and-go (`base`); none when that campaign failed."""
    return f"{row[key] / base[key]:5.2f}" if base is not None else f"{'n/a':>5}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robots", default="ur5e,ur10e")
    ap.add_argument("--seeds", type=int, default=1, help="stations per robot")
    ap.add_argument("--first-seed", type=int, default=0, help="the first station's seed")
    ap.add_argument("--speed", type=float, default=8.0, help="simulator speed (fast time)")
    ap.add_argument("--sweep-sim-speed", type=float,
                    help="simulator speed of the sweeps (default --speed): a station of the same seed (the "
                         "same arm) at this speed; 1 sweeps as a real station does (module docstring)")
    ap.add_argument("--poses", type=int, default=30, help="stop-and-go: method 000's pose count")
    ap.add_argument("--sweep-poses", type=int, default=12, help="sweep: the time-aware choice's pose count")
    ap.add_argument("--sweep-speeds", default="1.0,1.5", help="sweep tool speeds (m/s)")
    ap.add_argument("--sweep-samples", type=int, default=5, help="sweep: readings at each still pose")
    ap.add_argument("--held-out", type=int, default=300)
    args = ap.parse_args()
    limit_blas_threads()
    speeds = [float(v) for v in args.sweep_speeds.split(",")]
    print(f"{'robot':6} {'seed':>4} {'mode':16} {'robot s':>7} {'ratio':>5} {'moves':>6} {'meas':>5} "
          f"{'sweep':>6} {'still':>5} {'held':>4} {'rests':>5} {'segs':>4} {'val µm':>7} {'truth µm':>8} "
          f"{'t/SG':>5} "
          f"{'used':>6} {'wall s':>6}")
    for robot in args.robots.split(","):
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            sim = start_station(robot=robot, speed=args.speed, seed=seed, ideal=False, thermal=False)
            other = None
            try:
                with tempfile.TemporaryDirectory() as tmp:
                    path = Path(tmp) / "truth.json"
                    write_json(path, sim.info["services"][0]["truth"])
                    truth, _ = load_truth(path)
                held = held_out_poses(robot, truth, args.held_out, seed)
                cases = [("stop-and-go", config_for(sim, robot, campaign__calibration_poses=args.poses))]
                cases += [(f"sweep {v:.2f} m/s",
                           config_for(sim, robot, campaign__calibration_poses=args.sweep_poses,
                                      campaign__mode="sweep", campaign__sweep_speed=v,
                                      campaign__samples=args.sweep_samples)) for v in speeds]
                base = None
                for name, config in cases:
                    here, speed = sim, args.speed
                    if name != "stop-and-go" and args.sweep_sim_speed not in (None, args.speed):
                        if other is None:
                            other = start_station(robot=robot, speed=args.sweep_sim_speed, seed=seed,
                                                  ideal=False, thermal=False)
                        here, speed = other, args.sweep_sim_speed
                        svc = other.info["services"][0]
                        config = config.with_overrides(robot__address=other.address,
                                                       tracker__url=svc["tracker_emscon_url"])
                    try:
                        row = run(here, config, speed, truth, held)
                    except (RuntimeError, HilError) as exc:  # a failed campaign, or one refused
                        print(f"{robot:6} {seed:4d} {name:16} FAILED: {exc}", flush=True)
                        continue
                    if name == "stop-and-go":
                        base = row
                    print(f"{robot:6} {seed:4d} {name:16} {row['robot_time']:7.1f} "
                          f"{ratio(row, base, 'robot_time')} {row['moves']:6.1f} "
                          f"{row['measuring']:5.1f} {row['sweep']:6.1f} {row['still']:5d} {row['held']:4d} "
                          f"{row['rests']:5d} "
                          f"{row['segments']:4d} {row['validation_rms'] * 1e6:7.1f} "
                          f"{row['truth_rms'] * 1e6:8.1f} {ratio(row, base, 'truth_rms')} "
                          f"{row['used'] or 0:6d} {row['wall']:6.0f}  {row['status']}", flush=True)
            finally:
                sim.stop()
                if other is not None:
                    other.stop()


if __name__ == "__main__":
    main()
