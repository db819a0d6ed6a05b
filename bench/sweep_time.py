"""Robot time of a calibration: the time-aware stop-and-go campaign against a sweep, at the same accuracy.

Run from the repository root: ``PYTHONPATH=. python bench/sweep_time.py`` (``--quick``: one UR5e-or-UR10e
station per robot, one speed, one waypoint count). For each robot and station (a realistic truth,
`hil.calibration.synthetic.random_truth` with joint errors and lost motion, its tracker 2–4 m away):

* **Accuracy** is judged twice, as the truth error of the fitted model (noise-free): at the
  `--validation` poses both modes visit and measure statically (what a campaign reports; 20 poses are a
  noisy sample of it), and at `--held-out` further poses no mode visits (300: the model's accuracy
  over the workspace, the figure the 5 % criterion is read on). Both are drawn from the selector's
  feasible candidates for the station (`hil.calibration.selection.design_space`: reach, the tracker's
  range, acceptance and line of sight, the keep-in box). Held-out poses are approached from below in
  every joint, as the campaign engine approaches its poses.
* **Stop-and-go** (today's time-aware campaign): `hil.calibration.timed_selection.select_timed` chooses
  and orders the calibration poses for method 000's accuracy with `--poses` poses, the validation poses
  in the same tour; its robot time is the selector's own time model (the movej trapezoid at the
  station's default 0.5 rad/s and 1.0 rad/s², `hil.station.config`, plus the campaign's dwell per pose:
  5 readings of emScon's 0.5 s stationary measuring time, the overhead and the approach leg,
  `hil.campaign.chooser.pose_dwell`). The poses are measured with the tracker's noise (`Noise()`), each
  approached from below, and fitted by `identify` with compliance and the joint-angle harmonics of orders
  1–2 (the model class the sweep fits too, lost motion absorbed as the constant it is then).
* **Sweep** at each tool speed (`--speeds`) through `--waypoints` time-aware poses (a time-aware choice
  for that count — it may take a few more — or all of stop-and-go's): one tour
  (`hil.calibration.sweep_path.plan_sweep`) whose rests are the `--bootstrap` first waypoints and the
  validation poses, each held for the same dwell and measured statically from the side the tour
  arrives from; every joint's speed limit the tool speed over the arm's reach, its acceleration limit
  0.9 × the deflection model's quasi-static limit at the waypoints (`DynamicsModel.acceleration_limit`),
  so the fit can trust the samples. The tour is streamed by the simulator's clocks and noise
  (`hil.calibration.synthetic_stream.sweep_streams` along the tour: the controller at 500 Hz, the
  tracker at 1000 Hz, 35 ppm apart) and fitted by `hil.calibration.sweep_fit.fit_sweep` from the
  bootstrap's registration (its poses as static rows, compliance, the same harmonics and the lost
  motion, which the static rows against the moving ones identify). Robot time is the tour's duration.

Columns: mode, waypoints, tool speed, robot time, of which dwelling at rests and moving, the time ratio
to stop-and-go (target ≤ 1/3), validation and held-out RMS (µm) and the held-out ratio (target ≤ 1.05),
the clock offset's error against the simulator's truth and its stated σ, the trusted samples per second
of tour, the tour's RMS tool speed, the samples left out by reason, and the bench's own seconds.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from hil.arm.catalog import get_robot
from hil.arm.dynamics import DynamicsModel
from hil.arm.kinematics import Kinematics
from hil.arm.physical import typical_compliance
from hil.calibration.identification import identify, register
from hil.calibration.measurements import Measurements
from hil.calibration.selection import design_space
from hil.calibration.sweep_fit import fit_sweep
from hil.calibration.sweep_path import plan_sweep
from hil.calibration.synthetic import Noise, measure, random_truth, true_points
from hil.calibration.synthetic_stream import SplinePath, sweep_streams
from hil.calibration.timed_selection import select_timed
from hil.campaign.chooser import DWELL_OVERHEAD
from hil.campaign.steps import APPROACH, approach_seconds
from selector.candidates import Constraints
from selector.motion_time import Dwell

#: The station's default movej (`hil.station.config`: robot.speed 0.5 rad/s, robot.acceleration 1.0 rad/s²).
SPEED, ACCELERATION = 0.5, 1.0
#: The campaign's dwell per static pose (`hil.campaign.chooser.pose_dwell` with the defaults: "stable"
#: settling adds nothing beyond the readings, 5 readings × emScon's 0.5 s measuring time, the overhead and
#: the approach leg).
DWELL = Dwell(settle=0.0, measure=5 * 0.5, overhead=DWELL_OVERHEAD + approach_seconds(APPROACH, SPEED,
                                                                                     ACCELERATION))
#: Joint-angle harmonics of orders 1 and 2 of every joint (57 + 6j + 0..3) and the lost motion (93..98).
HARMONICS = [57 + 6 * j + k for j in range(6) for k in range(4)]
LOST_MOTION = list(range(93, 99))
UP = np.ones(6)


def truth_rms(truth, geometry, q: np.ndarray) -> float:
    d = np.tile(UP, (len(q), 1))
    e = Kinematics(geometry).points(q, directions=d) - true_points(truth, q, directions=d)
    return float(np.sqrt(np.mean(np.sum(e**2, axis=1))))


def static_measurements(truth, q: np.ndarray, rng: np.random.Generator) -> Measurements:
    q_read, p = measure(truth, q, Noise(), rng, directions=UP)
    return Measurements.from_arrays(q_read, p, directions=np.tile(UP, (len(q), 1)))


def station(robot: str, seed: int, args: argparse.Namespace) -> list[dict]:
    rng = np.random.default_rng(1000 + seed)
    truth = random_truth(robot, rng, ideal=False)
    spec = get_robot(robot)
    constraints = Constraints(tracker=tuple(map(float, truth.tracker.translation)))
    common = dict(smr=tuple(map(float, truth.smr)), constraints=constraints, compliance=True,
                  payload=truth.payload, gravity=None)
    _, cands, _ = design_space(robot, args.poses, candidates=args.candidates, seed=seed, scaling="expected",
                               say=lambda *_: None, **common)
    pick = rng.permutation(len(cands.q))
    validation = cands.q[pick[: args.validation]]
    held_out = cands.q[pick[args.validation: args.validation + args.held_out]]

    def accuracy(geometry) -> tuple[float, float]:
        return truth_rms(truth, geometry, validation), truth_rms(truth, geometry, held_out)

    t0 = time.perf_counter()
    timed = dict(speed=SPEED, acceleration=ACCELERATION, dwell=DWELL, fixed=validation,
                 candidates=args.candidates, seed=seed, time_limit=args.search_time, **common)
    report = select_timed(robot, args.poses, **timed)
    chosen = np.array(report["poses"])
    meas = static_measurements(truth, chosen, rng)
    sg = identify(meas, robot, compliance=True, payload=truth.payload, joint_errors=HARMONICS,
                  reject_outliers=False)
    rows = [dict(mode="stop-and-go", speed=None, waypoints=len(chosen),
                 time=report["predicted"]["robot_time"], rms=accuracy(sg.geometry),
                 took=time.perf_counter() - t0)]
    for count in args.waypoints:
        # the sweep's waypoints: the time-aware poses themselves, or a time-aware choice of fewer
        t0 = time.perf_counter()
        ways = chosen if count >= len(chosen) else np.array(select_timed(robot, count, **timed)["poses"])
        boot_q = ways[: args.bootstrap]
        # the bootstrap's first registration, as the campaign's bootstrap gives it before the sweep
        first = register(static_measurements(truth, boot_q, np.random.default_rng(seed)), robot,
                         smr_guess=truth.smr + 0.002)
        first.payload, first.compliance = truth.payload, typical_compliance(robot)
        limit = DynamicsModel(first).acceleration_limit(ways).min(axis=0)
        chose = time.perf_counter() - t0
        for v in args.speeds:
            t0 = time.perf_counter()
            joint_speed = np.minimum(v / spec.reach, spec.max_joint_speed)
            # one tour: the bootstrap and validation poses are its rests (each held for the campaign's
            # dwell and measured statically, from the side the tour arrives from), the waypoints swept
            tour = plan_sweep(ways, boot_q[0], max_speed=joint_speed, max_acceleration=0.9 * limit,
                              rate_hz=spec.rate_hz, spec=spec, stops=np.vstack([boot_q, validation]),
                              dwell_s=DWELL.seconds)
            directions = tour.approach_directions()
            is_boot = np.array([any(np.allclose(p, b) for b in boot_q) for p in tour.stops])
            q_read, p = measure(truth, tour.stops[is_boot], Noise(), rng, directions=directions[is_boot])
            boot = Measurements.from_arrays(q_read, p, directions=directions[is_boot])
            start = register(boot, robot, smr_guess=truth.smr + 0.002)
            start.payload, start.compliance = truth.payload, typical_compliance(robot)
            s = sweep_streams(truth, seed=seed, path=SplinePath(tour.t, tour.q))
            fit = fit_sweep(start, s.joints, s.tracker, static=boot, joint_errors=HARMONICS + LOST_MOTION)
            want = s.clocks.controller_from_tracker()
            c = fit.clock
            # the campaign's validation at its rests, each from the side the tour came from
            vq, vd = tour.stops[~is_boot], directions[~is_boot]
            e = Kinematics(fit.geometry).points(vq, directions=vd) - true_points(truth, vq, directions=vd)
            val = float(np.sqrt(np.mean(np.sum(e**2, axis=1))))
            moving = tour.duration - DWELL.seconds * len(tour.stops)
            rows.append(dict(mode="sweep", speed=v, waypoints=len(ways), time=tour.duration,
                             rms=(val, truth_rms(truth, fit.geometry, held_out)),
                             clock_err=float(c.map(c.t_ref) - want(c.t_ref)),
                             clock_sigma=c.sigma_at_ref_s, used_per_s=fit.trusted / tour.duration,
                             tour=moving, static=DWELL.seconds * len(tour.stops), v_rms=s.tool_speed_rms,
                             left=fit.left_out, took=chose + time.perf_counter() - t0))
            chose = 0.0
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default="ur5e,ur10e")
    parser.add_argument("--stations", type=int, default=2)
    parser.add_argument("--speeds", default="0.25,0.5,1.0", help="tool speeds (m/s) of the sweep")
    parser.add_argument("--poses", type=int, default=30, help="method 000's pose count (the accuracy)")
    parser.add_argument("--waypoints", default="12,99",
                        help="waypoint counts of the sweep (≥ the time-aware pose count: all of them)")
    parser.add_argument("--validation", type=int, default=20)
    parser.add_argument("--held-out", type=int, default=300)
    parser.add_argument("--bootstrap", type=int, default=8)
    parser.add_argument("--candidates", type=int, default=5000)
    parser.add_argument("--search-time", type=float, default=5.0)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    args.speeds = [float(v) for v in args.speeds.split(",")]
    args.waypoints = [int(v) for v in args.waypoints.split(",")]
    if args.quick:
        args.stations, args.speeds, args.waypoints = 1, args.speeds[1:2], args.waypoints[:1]
    print(f"{'robot':6} {'stn':>3} {'mode':11} {'ways':>4} {'v m/s':>5} {'robot s':>7} {'dwell s':>8} "
          f"{'move s':>6} {'time/SG':>7} {'val µm':>6} {'held µm':>7} {'held/SG':>7} {'clock err µs':>12} "
          f"{'σ µs':>5} {'used/s':>6} {'v_rms':>5} {'left out':>18} {'took s':>6}")
    for robot in args.robots.split(","):
        for seed in range(args.stations):
            rows = station(robot, seed, args)
            sg = rows[0]
            for r in rows:
                sweep = r["mode"] == "sweep"
                left = "" if not sweep else ",".join(f"{k[:4]}{v}" for k, v in r["left"].items() if v)
                cells = [f"{robot:6}", f"{seed:3d}", f"{r['mode']:11}", f"{r['waypoints']:4d}",
                         f"{r['speed'] or 0:5.2f}", f"{r['time']:7.1f}",
                         f"{r['static']:8.1f}" if sweep else f"{'':8}",
                         f"{r['tour']:6.1f}" if sweep else f"{'':6}",
                         f"{r['time'] / sg['time']:7.2f}", f"{r['rms'][0] * 1e6:6.1f}",
                         f"{r['rms'][1] * 1e6:7.1f}", f"{r['rms'][1] / sg['rms'][1]:7.2f}"]
                if sweep:
                    cells += [f"{r['clock_err'] * 1e6:12.2f}", f"{r['clock_sigma'] * 1e6:5.2f}",
                              f"{r['used_per_s']:6.0f}", f"{r['v_rms']:5.2f}", f"{left:>18}"]
                else:
                    cells += [f"{'':12}", f"{'':5}", f"{'':6}", f"{'':5}", f"{'':18}"]
                print(" ".join([*cells, f"{r['took']:6.1f}"]), flush=True)


if __name__ == "__main__":
    main()
