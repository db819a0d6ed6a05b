"""Robot time of a calibration: the time-aware stop-and-go campaign against a sweep, at the same accuracy.

Run from the repository root: ``PYTHONPATH=. python bench/sweep_time.py`` (``--quick``: one station per
robot, 1 m/s, the last waypoint count, a 2 s pose search). For each robot and station (a realistic truth,
`hil.calibration.synthetic.random_truth` with joint errors and lost motion, its tracker 2–4 m away):

* **Accuracy** is judged twice, as the truth error of the fitted model (noise-free): at the
  `--validation` poses both modes visit and measure statically (what a campaign reports; 20 poses are a
  noisy sample of it), and at `--held-out` further poses no mode visits (300: the model's accuracy
  over the workspace, the figure the 5 % criterion is read on). Both are drawn from the selector's
  feasible candidates for the station, in a draw of their own (not the candidates the selectors choose
  from, so no fit ever sees them) (`hil.calibration.selection.design_space`: reach, the tracker's
  range, acceptance and line of sight, the keep-in box). Held-out poses are approached from below in
  every joint, as the campaign engine approaches its poses. The validation poses are a two-stage
  cluster sample (`--clusters`, default 4: `campaign.validation_clusters`, as in the time-aware
  campaign's 135 s figure that issue's target is a third of; `selector.cluster_sample` with the
  chooser's weights), the held-out ones a simple random sample of the rest.
* **Stop-and-go** (today's time-aware campaign): `hil.calibration.timed_selection.select_timed` chooses
  and orders the calibration poses for method 000's accuracy with `--poses` poses, the validation poses
  in the same tour; its robot time is the selector's own time model (the movej trapezoid at the
  station's default 0.5 rad/s and 1.0 rad/s², `hil.station.config`, plus the campaign's dwell per pose:
  5 readings of emScon's 0.5 s stationary measuring time, the overhead and the approach leg,
  `hil.campaign.chooser.pose_dwell`). The poses are measured with the tracker's noise (`Noise()`), each
  approached from below, and fitted by `identify` with compliance and the joint-angle harmonics of orders
  1–2 (the model class the sweep fits too, lost motion absorbed as the constant it is then).
* **Sweep** at each tool speed (`--speeds`) for each `--waypoints` count and each `--bootstrap` count:
  one tour (`hil.calibration.sweep_path.plan_sweep`, ordered by the rest-to-rest leg time) whose rests
  are the bootstrap poses (spread along a time-aware choice of at least 12 poses) and the validation
  poses, and whose waypoints are the rest of that choice's first `--waypoints` poses (0: none, the tour
  is its rests and the legs between them, all of it streamed). A validation rest is stop-and-go's pose:
  held for the campaign's dwell (approach leg included, so approached from below in every joint as the
  engine does), with `--val-readings` emScon readings (default 5, the campaign's; 1: what a rest in
  a streaming tour needs, its stillness seen in the 1 kHz stream — `validation_dwell`). A bootstrap rest
  is held for `--boot-readings` emScon readings and the overhead (no approach leg: the fit takes it from
  the side the tour arrives from); its static rows' noise is
  scaled by √(5/readings) against the bench's 5-reading poses. Every joint's speed limit is the tool
  speed over the arm's reach, its acceleration limit `--acceleration` × the deflection model's
  quasi-static limit at the tour's poses (`DynamicsModel.acceleration_limit`), so the fit can trust the
  samples. The tour is streamed by the simulator's clocks and noise
  (`hil.calibration.synthetic_stream.sweep_streams` along the tour: the controller at 500 Hz, the
  tracker at 1000 Hz, 35 ppm apart), the validation rests' stretches are cut out of the tracker
  stream (`sweep_fit.without_intervals`, ± 50 ms: the fit never sees a validation pose), and it is
  fitted by `hil.calibration.sweep_fit.fit_sweep` from the bootstrap's registration (its poses as
  static rows, compliance, the same harmonics and the lost motion, which the static rows against the
  moving ones identify). Robot time is the tour's duration.

Columns: mode; pose: calibration poses visited (stop-and-go's measured poses; a sweep's rests and
waypoints); boot: the sweep's bootstrap rests; tool speed; robot time, of which dwelling at rests and
moving; the time ratio to stop-and-go (target ≤ 1/3); **cal s, cal/SG: the calibration part alone**
— the robot time of a tour acquiring the calibration data without the validation (stop-and-go: its
chosen poses' own best movej tour with their dwell; sweep: the same sweep without the validation
rests) and its ratio, a separate figure beside the whole campaign's, never instead of it; val s: the
validation alone, its poses in their own best tour with the campaign's dwell (stop-and-go's movej;
the sweep's limits), the least any tour measuring it takes; validation and held-out RMS (µm) and
the held-out ratio (target ≤ 1.05); the clock offset's error against the simulator's truth and its
stated σ; the trusted samples per second of tour; the tour's RMS tool speed; the samples left out by
reason (the validation rests cut out are not counted; the 50 ms after each is, as "after a gap"); and
the bench's own seconds. Stop-and-go's tour comes from a search of `--search-time` wall seconds, so
a loaded host may find a slightly different tour (±1 pose, ±2 s).
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
from hil.calibration.sweep_fit import fit_sweep, without_intervals
from hil.calibration.sweep_path import plan_sweep
from hil.calibration.synthetic import Noise, measure, random_truth, true_points
from hil.calibration.synthetic_stream import SplinePath, sweep_streams
from hil.calibration.timed_selection import select_timed
from hil.campaign.chooser import DWELL_OVERHEAD
from hil.campaign.steps import APPROACH, approach_seconds
from selector.candidates import Constraints
from selector.cluster_sample import cluster_sample
from selector.motion_time import Dwell, MotionProfile
from selector.order import order_poses

#: The station's default movej (`hil.station.config`: robot.speed 0.5 rad/s, robot.acceleration 1.0 rad/s²).
SPEED, ACCELERATION = 0.5, 1.0
#: The campaign's dwell per static pose (`hil.campaign.chooser.pose_dwell` with the defaults: "stable"
#: settling adds nothing beyond the readings, 5 readings × emScon's 0.5 s measuring time, the overhead and
#: the approach leg).
READINGS, READING_S = 5, 0.5
DWELL = Dwell(settle=0.0, measure=READINGS * READING_S,
              overhead=DWELL_OVERHEAD + approach_seconds(APPROACH, SPEED, ACCELERATION))
#: Seconds either side of a validation rest whose tracker samples the fit does not get (`without_rests`):
#: hil's choice, 50 × the join's worst first-map error seen (~1 ms) and a negligible share of a tour.
REST_MARGIN_S = 0.05
#: Seed offset of the validation and held-out poses' candidate draw (`station`): any other than the
#: selectors' own seeds.
UNSEEN = 7919
#: The fewest poses `select_timed` chooses (the 31 parameters of the fitted class, 3 coordinates a pose);
#: a sweep through fewer waypoints takes the first of those in the tour's order.
FEWEST = 12
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


def boot_dwell(readings: int) -> float:
    """Seconds a bootstrap rest of the sweep holds: `readings` emScon stationary readings (0.5 s each,
    as the campaign's) and the campaign's overhead, no approach leg — the fit takes a bootstrap pose
    from the side the tour arrives from (its lost motion's sign is known), so no move from below.
    A stop-and-go pose's 5 readings are also its stillness check (`hil.campaign.stillness`); at a
    sweep's rest the tracker keeps streaming at 1 kHz, which shows the arm still or not, so one reading
    is assumed enough there (an assumption: the online half must check the stream's stillness)."""
    return readings * READING_S + DWELL_OVERHEAD


def validation_dwell(readings: int) -> float:
    """Seconds a sweep's validation rest holds: `readings` emScon readings of 0.5 s, the overhead and the
    approach leg from below (at the station's movej, as stop-and-go's). Five (the default) is the
    campaign's `campaign.samples`, the same dwell as stop-and-go's poses; fewer is what a rest in a
    streaming tour could hold, its stillness seen in the 1 kHz stream rather than in the spread of five
    readings. The accuracy columns are truth errors, so the readings change the time alone; what one
    reading costs the validation RMS a campaign reports is its noise, √5 × a 5-reading pose's."""
    return readings * READING_S + DWELL.overhead


def boot_noise(readings: int) -> Noise:
    """The static rows' noise for `readings` readings: this bench's static poses (5 readings) are drawn
    with one reading's σ (`Noise()`, both modes alike: pessimistic by √5 for both), so n readings get
    √(5/n) of it — fewer readings cost the bootstrap rows exactly the averaging they lose."""
    k = np.sqrt(READINGS / readings)
    return Noise(distance_sigma=Noise().distance_sigma * k, angle_sigma=Noise().angle_sigma * k)


def rest_intervals(clocks, tour, rests: np.ndarray, dwell: float) -> list[tuple[float, float]]:
    """The tracker-clock stretches while the arm rests at the validation poses (± `REST_MARGIN_S`), for
    `without_intervals`: the fit must never see a validation pose. A campaign marks them by the
    controller's timestamps and the join's first clock map (good to milliseconds); the bench maps the
    tour's times through the simulator's tracker clock, and the margin covers far more than the
    difference."""
    return [tuple(map(float, clocks.tracker.reading(np.array([ts - REST_MARGIN_S,
                                                               ts + dwell + REST_MARGIN_S]))))
            for ts in tour.stop_times[rests]]


def station(robot: str, seed: int, args: argparse.Namespace) -> list[dict]:
    rng = np.random.default_rng(1000 + seed)
    truth = random_truth(robot, rng, ideal=False)
    spec = get_robot(robot)
    constraints = Constraints(tracker=tuple(map(float, truth.tracker.translation)))
    common = dict(smr=tuple(map(float, truth.smr)), constraints=constraints, compliance=True,
                  payload=truth.payload, gravity=None)
    # validation and held-out poses from a draw of their own: the selectors draw their candidates with
    # `seed`, and a validation pose among them is one they may choose (a free pose to a time-aware
    # tour) — then a fit would see it
    _, cands, _ = design_space(robot, args.poses, candidates=args.candidates, seed=UNSEEN + seed,
                               scaling="expected", say=lambda *_: None, **common)
    pick = rng.permutation(len(cands.q))
    movej = MotionProfile(SPEED, ACCELERATION, tuple(map(float, spec.max_joint_speed)))
    if args.clusters:  # clustered validation (`campaign.validation_clusters`, the chooser's rule)
        sample = cluster_sample(cands.q, args.validation, args.clusters, scale=1.0 / movej.joint_speeds,
                                seed=UNSEEN + seed)
        validation = cands.q[sample.indices]
        rest = np.setdiff1d(pick, sample.indices, assume_unique=True)
    else:
        validation, rest = cands.q[pick[: args.validation]], pick[args.validation:]
    held_out = cands.q[rest[: args.held_out]]

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
    # the calibration part alone: the same poses' own best tour at the station's movej, with their dwell
    calibration = order_poses(chosen, profile=movej)[1] + DWELL.seconds * len(chosen)
    validation_only = order_poses(validation, profile=movej)[1] + DWELL.seconds * len(validation)
    rows = [dict(mode="stop-and-go", speed=None, waypoints=len(chosen), boot=0,
                 time=report["predicted"]["robot_time"], calibration=calibration, rms=accuracy(sg.geometry),
                 static=DWELL.seconds * (len(chosen) + len(validation)), validation_only=validation_only,
                 took=time.perf_counter() - t0)]
    rows[0]["tour"] = rows[0]["time"] - rows[0]["static"]
    pools: dict[int, np.ndarray] = {}
    for count, n_boot in [(c, b) for c in args.waypoints for b in args.bootstrap]:
        # the sweep's waypoints: the time-aware poses themselves, or a time-aware choice of fewer (the
        # bootstrap poses among them), or none: the tour is then its rests and the legs between them
        t0 = time.perf_counter()
        size = max(count, n_boot, FEWEST)
        if size not in pools:
            pools[size] = (chosen if count >= len(chosen)
                           else np.array(select_timed(robot, size, **timed)["poses"]))
        pool = pools[size]
        # the bootstrap: poses spread along the tour (its visiting order), so spread in the workspace
        pick_boot = np.zeros(len(pool), dtype=bool)
        pick_boot[np.unique(np.linspace(0, len(pool) - 1, n_boot).round().astype(int))] = True
        boot_q = pool[pick_boot]
        # the sweep's waypoints: the rest of the first `count`, less the bootstrap (the tour rests at those)
        ways = pool[: count][~pick_boot[: count]]
        # the bootstrap's first registration, as the campaign's bootstrap gives it before the sweep
        first = register(static_measurements(truth, boot_q, np.random.default_rng(seed)), robot,
                         smr_guess=truth.smr + 0.002)
        first.payload, first.compliance = truth.payload, typical_compliance(robot)
        limit = DynamicsModel(first).acceleration_limit(np.vstack([pool, validation])).min(axis=0)
        chose = time.perf_counter() - t0
        boot_s = boot_dwell(args.boot_readings)
        val_s = validation_dwell(args.val_readings)
        for v in args.speeds:
            t0 = time.perf_counter()
            joint_speed = np.minimum(v / spec.reach, spec.max_joint_speed)
            plan = dict(max_speed=joint_speed, max_acceleration=args.acceleration * limit,
                        rate_hz=spec.rate_hz, spec=spec)
            # one tour: the bootstrap and validation poses are its rests, the waypoints swept. A validation
            # rest is stop-and-go's: held for the campaign's dwell, approach leg included, so approached
            # from below in every joint as the engine does; a bootstrap rest is held for its readings and
            # measured from the side the tour arrives from (the fit is told which)
            stops = np.vstack([boot_q, validation])
            dwell = np.r_[np.full(len(boot_q), boot_s), np.full(len(validation), val_s)]
            tour = plan_sweep(ways, boot_q[0], stops=stops, dwell_s=dwell, **plan)
            # the calibration part alone: the same sweep without the validation rests
            cal_tour = plan_sweep(ways, boot_q[0], stops=boot_q, dwell_s=boot_s, **plan)
            # and the validation alone at the sweep's limits: what any tour measuring it costs at least
            val_tour = plan_sweep(np.zeros((0, 6)), validation[0], stops=validation, dwell_s=val_s, **plan)
            directions = tour.approach_directions()
            is_boot = np.array([any(np.allclose(p, b) for b in boot_q) for p in tour.stops])
            q_read, p = measure(truth, tour.stops[is_boot], boot_noise(args.boot_readings), rng,
                                directions=directions[is_boot])
            boot = Measurements.from_arrays(q_read, p, directions=directions[is_boot])
            start = register(boot, robot, smr_guess=truth.smr + 0.002)
            start.payload, start.compliance = truth.payload, typical_compliance(robot)
            s = sweep_streams(truth, seed=seed, path=SplinePath(tour.t, tour.q))
            tracker = without_intervals(s.tracker, rest_intervals(s.clocks, tour, ~is_boot, val_s))
            fit = fit_sweep(start, s.joints, tracker, static=boot, joint_errors=HARMONICS + LOST_MOTION)
            want = s.clocks.controller_from_tracker()
            c = fit.clock
            static = float(dwell.sum())
            rows.append(dict(mode="sweep", speed=v, waypoints=len(ways) + len(boot_q), boot=len(boot_q),
                             time=tour.duration, calibration=cal_tour.duration,
                             validation_only=val_tour.duration,
                             rms=accuracy(fit.geometry),
                             clock_err=float(c.map(c.t_ref) - want(c.t_ref)),
                             clock_sigma=c.sigma_at_ref_s, used_per_s=fit.trusted / tour.duration,
                             tour=tour.duration - static, static=static, v_rms=s.tool_speed_rms,
                             left=fit.left_out, took=chose + time.perf_counter() - t0))
            chose = 0.0
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default="ur5e,ur10e")
    parser.add_argument("--stations", type=int, default=2)
    parser.add_argument("--speeds", default="0.5,1.0,1.5", help="tool speeds (m/s) of the sweep")
    parser.add_argument("--poses", type=int, default=30, help="method 000's pose count (the accuracy)")
    parser.add_argument("--waypoints", default="0,12",
                        help="waypoint counts of the sweep (0: its rests alone; ≥ the time-aware pose "
                             "count: all of them)")
    parser.add_argument("--validation", type=int, default=20)
    parser.add_argument("--clusters", type=int, default=4,
                        help="validation poses in this many clusters (`campaign.validation_clusters`, "
                             "the time-aware campaign's 135 s figure); 0: a simple random sample")
    parser.add_argument("--held-out", type=int, default=300)
    parser.add_argument("--bootstrap", default="8",
                        help="static rests the sweep's fit registers on (a comma list: one sweep each)")
    parser.add_argument("--boot-readings", type=int, default=1,
                        help="emScon stationary readings at each bootstrap rest (validation rests: always 5)")
    parser.add_argument("--val-readings", type=int, default=READINGS,
                        help="emScon readings at each validation rest of a sweep (stop-and-go: always 5)")
    parser.add_argument("--acceleration", type=float, default=0.9,
                        help="the sweep's joint acceleration limit × the deflection model's quasi-static one")
    parser.add_argument("--candidates", type=int, default=5000)
    parser.add_argument("--search-time", type=float, default=5.0)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    args.speeds = [float(v) for v in args.speeds.split(",")]
    args.waypoints = [int(v) for v in args.waypoints.split(",")]
    args.bootstrap = [int(v) for v in args.bootstrap.split(",")]
    if args.quick:
        args.stations, args.speeds, args.waypoints = 1, [1.0], args.waypoints[-1:]
        args.search_time = 2.0
    print(f"{'robot':6} {'stn':>3} {'mode':11} {'pose':>4} {'boot':>4} {'v m/s':>5} {'robot s':>7} "
          f"{'dwell s':>7} {'move s':>6} {'time/SG':>7} {'cal s':>6} {'cal/SG':>6} {'val µm':>6} "
          f"{'held µm':>7} {'held/SG':>7} {'clock err µs':>12} {'σ µs':>5} {'used/s':>6} {'v_rms':>5} "
          f"{'left out':>18} {'took s':>6}")
    floors = []
    for robot in args.robots.split(","):
        for seed in range(args.stations):
            rows = station(robot, seed, args)
            sg = rows[0]
            floors.append((robot, seed, sg["validation_only"], sg["validation_only"] / sg["time"]))
            for r in rows:
                sweep = r["mode"] == "sweep"
                left = "" if not sweep else ",".join(f"{k[:4]}{v}" for k, v in r["left"].items() if v)
                cells = [f"{robot:6}", f"{seed:3d}", f"{r['mode']:11}", f"{r['waypoints']:4d}",
                         f"{r['boot']:4d}", f"{r['speed'] or 0:5.2f}", f"{r['time']:7.1f}",
                         f"{r['static']:7.1f}", f"{r['tour']:6.1f}", f"{r['time'] / sg['time']:7.2f}",
                         f"{r['calibration']:6.1f}", f"{r['calibration'] / sg['calibration']:6.2f}",
                         f"{r['validation_only']:6.1f}",
                         f"{r['rms'][0] * 1e6:6.1f}", f"{r['rms'][1] * 1e6:7.1f}",
                         f"{r['rms'][1] / sg['rms'][1]:7.2f}"]
                if sweep:
                    cells += [f"{r['clock_err'] * 1e6:12.2f}", f"{r['clock_sigma'] * 1e6:5.2f}",
                              f"{r['used_per_s']:6.0f}", f"{r['v_rms']:5.2f}", f"{left:>18}"]
                else:
                    cells += [f"{'':12}", f"{'':5}", f"{'':6}", f"{'':5}", f"{'':18}"]
                print(" ".join([*cells, f"{r['took']:6.1f}"]), flush=True)
    print("\nval s: the validation alone (its static poses in their own best tour, each with the campaign's "
          "dwell;\nstop-and-go at the station's movej, a sweep at its own limits):")
    for robot, seed, t, ratio in floors:
        print(f"  {robot} station {seed}: at movej {t:.1f} s = {ratio:.2f} × stop-and-go's robot time")


if __name__ == "__main__":
    main()
