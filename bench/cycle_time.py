"""End-of-line cycle time: robot time to reach today's accuracy, UR5e and UR10e, in one run.

Each station (seed) is a realistic arm (placement errors, compliant joints, the SMR's payload; warm, so no
thermal drift: the warm-up is the same for every method and is left out) with the tracker at a known
position, at the example configuration (hil/station/station.example.toml: 0.5 rad/s, 1 rad/s², fixed
settle 0.3 s, 5 tracker samples, 30 calibration + 20 validation poses, its keep-in box).

Rows (validation: the same 20 random poses in every row):

* **today**: method 000 (tabu, O1) for 30 poses, ordered by the slowest joint at its maximum speed,
  then the validation poses in their own tour; fixed settle — hil before this issue;
* **random + best tour**: random poses, as many as it takes to reach today's accuracy, one tour with the
  validation poses under the driver's movej profile from where the arm stands; fixed settle;
* **method 000 + best tour**: today's 30 poses in that one tour; fixed settle;
* **time-aware**: `campaign.selection = "time-aware"` (poses and tour together, target: today's predicted
  accuracy) and `robot.settle = "stable"` (measure once the tracker's readings agree);
* **time-aware, clustered validation**: the same, with `campaign.validation_clusters = K`: the 20
  validation poses are a two-stage cluster sample (K clusters drawn with probability proportional to
  their size, 20/K poses drawn in each: every candidate equally likely, so the validation RMS stays an
  unbiased estimate of the workspace's; its spread is larger, shown as the design effect);
* **physical limit** of the time-aware tour: its moves at the profile's minimum times plus the tracker's
  measuring time (samples × one reading), nothing else.

**Accuracy** (part A, many noise draws, no simulator): the truth error of the identified model on 500
held-out poses of the same constrained workspace, RMS over seeds × draws. "Equal accuracy" is within 5 %
of today's. **Robot time** (part B, the simulators): each campaign runs on the simulated station (the
real ur_rtde and GeoCOM clients) and its robot time is what the simulators account on their own clock:
seconds the controller ran joint moves, seconds the tracker spent measuring, plus the fixed settle waits
and the joint readings (10 RTDE frames at 500 Hz per visit). Fast-time software overhead (every wall
millisecond is `--speed` simulated ones) is left out of that and shown as "sim clock" beside it. The sim
campaigns' own validation RMS and truth error are shown too.

The time-aware rows search for ``campaign.search_time`` seconds (the example's 10 s; ``--search-time``)
before the first move: wall time of the cell, not robot time, shown as "selection compute" per station.

Run: python bench/cycle_time.py [--seeds 3] [--draws 4] [--speed 10] [--robots ur5e,ur10e] [--clusters 4]
[--search-time S] [--joint-errors none|auto|ORDERS]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from hil.arm.blas_threads import limit_blas_threads
from hil.arm.geometry import Geometry, look_at_tracker
from hil.calibration.identification import identify
from hil.calibration.measurements import Measurements
from hil.calibration.model_file import truth_document
from hil.calibration.selection import design_space, parse_constraints
from hil.calibration.synthetic import Noise, measure, random_truth, true_points
from hil.campaign.calibration_plan import CALIBRATION, VALIDATION, Choice, SelectionRequest
from hil.campaign.chooser import (
    ACCEPTANCE_MARGIN_DEG,
    CAMPAIGN_LOWER,
    CAMPAIGN_UPPER,
    campaign_chooser,
    pose_dwell,
)
from hil.campaign.engine import RealClock
from hil.campaign.events import EventBus
from hil.campaign.runner import run_campaign
from hil.station.config import load_config
from hil.station.devices import open_devices
from mocks.station import start_station
from selector.motion_time import MotionProfile
from selector.order import order_poses

EXAMPLE = Path(__file__).resolve().parent.parent / "hil" / "station" / "station.example.toml"
HELD_OUT = 500
TOLERANCE = 1.05  # "within 5 % of today's result"
RANDOM_COUNTS = (30, 40, 50, 60, 75, 90, 110, 130)
RTDE_PERIOD = 0.002  # e-Series RTDE at 500 Hz


def station_config(robot: str, truth: Geometry, sim: Any = None, **over: Any) -> Any:
    """The example configuration for this arm and tracker (and simulator, when given)."""
    base = load_config(EXAMPLE)
    known = dict(robot__type=robot, tracker__position=[float(v) for v in truth.tracker.translation],
                 smr__offset=[float(v) for v in truth.smr], warmup__enabled=False, drift__every=0,
                 robot__payload={"mass": truth.payload.mass, "com": [float(v) for v in truth.payload.com]},
                 campaign__candidates=20000)
    if sim is not None:
        known.update(robot__address=sim.address, tracker__url=sim.info["services"][0]["tracker_url"])
    return base.with_overrides(**(known | over))


def requests(config: Any, truth: Geometry) -> dict[str, Any]:
    model = Geometry.nominal(config.robot["type"], truth.smr, look_at_tracker(config.tracker["position"]))
    keep_in = (np.array(config.keep_in["min"]), np.array(config.keep_in["max"]))
    return dict(model=model, keep_in=keep_in, acceptance_angle=config.smr["acceptance_angle"],
                index=config.campaign["index"], candidates=config.campaign["candidates"])


def constraints_of(config: Any) -> Any:
    return parse_constraints(
        tracker=tuple(config.tracker["position"]),
        half_angle_deg=max(1.0, config.smr["acceptance_angle"] - ACCEPTANCE_MARGIN_DEG),
        keep_in_lower=tuple(config.keep_in["min"]), keep_in_upper=tuple(config.keep_in["max"]),
        floor=float(config.keep_in["min"][2]), joint_lower=CAMPAIGN_LOWER, joint_upper=CAMPAIGN_UPPER)


def truth_error(truth: Geometry, Q: np.ndarray, qv: np.ndarray, config: Any, rng: np.random.Generator,
                draws: int) -> float:
    """Mean squared truth error (m²) on held-out `qv` of models identified from poses `Q`."""
    out = []
    for _ in range(draws):
        q, p = measure(truth, Q, Noise(), rng)
        fit = identify(Measurements(q, p, np.arange(1, len(q) + 1)), config.robot["type"], truth.smr,
                       compliance=True, payload=config.payload, gravity=config.gravity)
        e = true_points(fit.geometry, qv) - true_points(truth, qv)
        out.append(float(np.mean(np.sum(e * e, axis=1))))
    return float(np.mean(out))


def plan_station(robot: str, seed: int, draws: int, home: np.ndarray, clusters: int,
                 search_time: float | None = None, over: dict[str, Any] | None = None) -> dict[str, Any]:
    """Part A for one station: every method's poses and tour, and their truth errors (`over`: further
    configuration overrides, e.g. ``campaign__joint_errors``)."""
    rng = np.random.default_rng(7000 + seed)
    truth = random_truth(robot, rng)
    truth.thermal = None  # warm: the warm-up is the same for every method
    config = station_config(robot, truth, **(over or {}))
    base = requests(config, truth)
    camp = config.campaign
    today_choose = campaign_chooser(config)
    t0 = time.perf_counter()
    cal = today_choose(SelectionRequest(CALIBRATION, camp["calibration_poses"], seed=camp["seed"],
                                        exclude=np.zeros((0, 6)), **base))
    val = today_choose(SelectionRequest(VALIDATION, camp["validation_poses"], seed=camp["seed"] + 1,
                                        exclude=cal.poses, start=cal.poses[-1], **base))
    today_seconds = time.perf_counter() - t0
    timed_config = config.with_overrides(campaign__selection="time-aware", robot__settle="stable",
                                         **({} if search_time is None else
                                            {"campaign__search_time": search_time}))
    t0 = time.perf_counter()
    timed = campaign_chooser(timed_config)(SelectionRequest(
        CALIBRATION, camp["calibration_poses"], seed=camp["seed"], exclude=val.poses, start=home,
        fixed=val.poses, **base))
    timed_seconds = time.perf_counter() - t0
    clustered_config = timed_config.with_overrides(campaign__validation_clusters=clusters)
    clustered_choose = campaign_chooser(clustered_config)
    val_c = clustered_choose(SelectionRequest(VALIDATION, camp["validation_poses"], seed=camp["seed"] + 1,
                                              exclude=np.zeros((0, 6)), start=home, **base))
    timed_c = clustered_choose(SelectionRequest(
        CALIBRATION, camp["calibration_poses"], seed=camp["seed"], exclude=val_c.poses, start=home,
        fixed=val_c.poses, **base))
    # the workspace: the same constraints' candidates, another seed, for random poses and held-out ones
    _, cands, _ = design_space(robot, camp["calibration_poses"], candidates=4000, seed=seed + 99,
                               smr=truth.smr, constraints=constraints_of(config), scaling="expected",
                               compliance=True, payload=config.payload, gravity=config.gravity,
                               say=lambda *_: None)
    order = rng.permutation(len(cands.q))
    qv = cands.q[order[:HELD_OUT]]
    pool = cands.q[order[HELD_OUT:]]
    err = {"today": truth_error(truth, cal.poses, qv, config, rng, draws),
           "time-aware": truth_error(truth, timed.poses, qv, config, rng, draws),
           "time-aware, clustered validation": truth_error(truth, timed_c.poses, qv, config, rng, draws)}
    random_err = {n: truth_error(truth, pool[:n], qv, config, rng, draws) for n in RANDOM_COUNTS}
    return {"truth": truth, "config": config, "cal": cal, "val": val, "timed": timed, "pool": pool,
            "val_c": val_c, "timed_c": timed_c, "clustered_config": clustered_config,
            "errors": err, "random": random_err, "timed_seconds": timed_seconds,
            "today_seconds": today_seconds}


def best_tour(cal: np.ndarray, val: np.ndarray, profile: MotionProfile, home: np.ndarray) -> list[dict]:
    """One tour through calibration and validation poses from `home` (the plan's "tour" format)."""
    both = np.vstack([cal, val])
    perm, _ = order_poses(both, profile=profile, start=home)
    return [{"role": "selected", "index": int(k)} if k < len(cal)
            else {"role": "fixed", "index": int(k - len(cal))} for k in perm]


def given_poses(cal: np.ndarray, val: np.ndarray, tour: list[dict] | None) -> Any:
    """A chooser answering with poses chosen beforehand (the rows are measured on the simulator)."""
    def choose(request: SelectionRequest) -> Choice:
        if request.role == CALIBRATION:
            return Choice(np.asarray(cal), {"method": "given", **({"tour": tour} if tour else {})})
        return Choice(np.asarray(val), {"method": "given"})
    return choose


def run_row(sim: Any, config: Any, choose: Any, home: np.ndarray, speed: float, truth: Geometry,
            qv: np.ndarray) -> dict[str, float]:
    """One campaign on the simulator: robot time by the simulators' own account, and its accuracy."""
    sim.inject("set_joints", q=home.tolist())
    before = sim.state()
    out = run_campaign(config, choose, bus=EventBus(), campaign=f"c{time.monotonic_ns()}",
                       clock=RealClock(speed), devices=open_devices(config))
    after = sim.state()
    if out.result is None:
        raise RuntimeError(f"the campaign ended {out.status}: {out.error}")
    r = out.result
    visits = len(r.records)
    moves = after["motion_seconds"] - before["motion_seconds"]
    s_before, s_after = before["services"], after["services"]
    measuring = s_after["tracker_measuring_seconds"] - s_before["tracker_measuring_seconds"]
    settle = config.robot["settle_time"] * visits if config.robot["settle"] == "fixed" else 0.0
    joints = visits * config.robot["joint_samples"] * RTDE_PERIOD
    e = true_points(r.fit.geometry, qv) - true_points(truth, qv)
    t = out.timing
    return {"robot_time": moves + measuring + settle + joints, "moves": moves, "measuring": measuring,
            "settle": settle, "visits": visits, "sim_clock": (t["total"] - t["compute"]) * speed,
            "validation_rms": r.after.rms, "truth_rms": float(np.sqrt(np.mean(np.sum(e * e, axis=1)))),
            "readings": s_after["tracker_measurements"] - s_before["tracker_measurements"]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--draws", type=int, default=4, help="noise draws per station for the accuracy")
    ap.add_argument("--speed", type=float, default=10.0, help="simulator speed (fast time)")
    ap.add_argument("--robots", default="ur5e,ur10e")
    ap.add_argument("--json", help="write every figure here too")
    ap.add_argument("--clusters", type=int, default=4, help="validation clusters of the clustered row")
    ap.add_argument("--search-time", type=float, help="campaign.search_time of the time-aware rows "
                                                       "(default: the example configuration's)")
    ap.add_argument("--joint-errors", help="campaign.joint_errors of every row (default: the example "
                                           "configuration's; the README's table was measured with none)")
    args = ap.parse_args()
    over = {} if args.joint_errors is None else {"campaign__joint_errors": args.joint_errors}
    limit_blas_threads()  # as the CLI does: one BLAS thread (hil.arm.blas_threads)
    report: dict[str, Any] = {}
    for robot in args.robots.split(","):
        rows: dict[str, list[dict[str, float]]] = {}
        acc: dict[str, list[float]] = {"today": [], "time-aware": [], "time-aware, clustered validation": []}
        rand: dict[int, list[float]] = {n: [] for n in RANDOM_COUNTS}
        stations = []
        failed: dict[str, list[int]] = {}
        for seed in range(args.seeds):
            with tempfile.TemporaryDirectory() as tmp:
                # the simulator first: its home pose is where every tour starts
                rng = np.random.default_rng(7000 + seed)
                truth = random_truth(robot, rng)
                truth.thermal = None
                path = Path(tmp) / "truth.json"
                path.write_text(json.dumps(truth_document(truth, Noise())))
                sim = start_station(robot=robot, truth=str(path), speed=args.speed, seed=seed)
                try:
                    home = np.asarray(sim.info["services"][0]["home"], dtype=float)
                    st = plan_station(robot, seed, args.draws, home, args.clusters, args.search_time, over)
                    stations.append(st)
                    for k, v in st["errors"].items():
                        acc[k].append(v)
                    for n, v in st["random"].items():
                        rand[n].append(v)
                    config = station_config(robot, truth, sim, **over)
                    profile = MotionProfile(config.robot["speed"], config.robot["acceleration"],
                                            tuple(st["timed"].info["motion"]["max_joint_speed"]))
                    cal, val = st["cal"].poses, st["val"].poses
                    today_rms = float(np.sqrt(np.mean(acc["today"])))
                    n_random = next((n for n in RANDOM_COUNTS
                                     if np.sqrt(np.mean(rand[n])) <= TOLERANCE * today_rms),
                                    RANDOM_COUNTS[-1])
                    qv = st["pool"][:HELD_OUT]
                    fixed_settle = dict(robot__settle="fixed")
                    extra = st["pool"][HELD_OUT:HELD_OUT + n_random]
                    cases = {
                        "today": (config.with_overrides(**fixed_settle), given_poses(cal, val, None)),
                        "random + best tour": (
                            config.with_overrides(campaign__selection="time-aware", **fixed_settle),
                            given_poses(extra, val, best_tour(extra, val, profile, home))),
                        "method 000 + best tour": (
                            config.with_overrides(campaign__selection="time-aware", **fixed_settle),
                            given_poses(cal, val, best_tour(cal, val, profile, home))),
                        "time-aware": (
                            config.with_overrides(campaign__selection="time-aware", robot__settle="stable"),
                            given_poses(st["timed"].poses, val, st["timed"].info["tour"])),
                        "time-aware, clustered validation": (
                            station_config(robot, truth, sim, **over).with_overrides(
                                campaign__selection="time-aware", robot__settle="stable",
                                campaign__validation_clusters=args.clusters),
                            given_poses(st["timed_c"].poses, st["val_c"].poses, st["timed_c"].info["tour"])),
                    }
                    for name, (cfg, choose) in cases.items():
                        try:
                            row = run_row(sim, cfg, choose, home, args.speed, truth, qv)
                        except RuntimeError as exc:  # e.g. too many poses skipped to identify
                            print(f"{robot} seed {seed} {name:<34} FAILED: {exc}", flush=True)
                            failed.setdefault(name, []).append(seed)
                            continue
                        row["poses"] = {"random + best tour": n_random, "time-aware": len(st["timed"].poses),
                                        "time-aware, clustered validation": len(st["timed_c"].poses)
                                        }.get(name, len(cal))
                        rows.setdefault(name, []).append(row)
                        print(f"{robot} seed {seed} {name:<34} robot {row['robot_time']:7.1f} s "
                              f"(moves {row['moves']:.1f}, measuring {row['measuring']:.1f}, settle "
                              f"{row['settle']:.1f}), sim clock {row['sim_clock']:.0f} s, validation "
                              f"{row['validation_rms'] * 1e6:.1f} µm, truth {row['truth_rms'] * 1e6:.1f} µm, "
                              f"{row['visits']} poses measured",
                              flush=True)
                    dwell = pose_dwell(cases["time-aware"][0])
                    limits = (("physical limit", st["timed"], val),
                              ("physical limit, clustered", st["timed_c"], st["val_c"].poses))
                    for label, chosen, fixed in limits:
                        tour = np.array([chosen.poses[s["index"]] if s["role"] == "selected"
                                         else fixed[s["index"]] for s in chosen.info["tour"]])
                        limit = profile.tour_time(tour, home) + len(tour) * dwell.measure
                        rows.setdefault(label, []).append({"robot_time": limit})
                finally:
                    sim.stop()
        today_rms = float(np.sqrt(np.mean(acc["today"])))
        n_random = next((n for n in RANDOM_COUNTS if np.sqrt(np.mean(rand[n])) <= TOLERANCE * today_rms),
                        RANDOM_COUNTS[-1])
        truth_rms = {"today": today_rms, "method 000 + best tour": today_rms,
                     "time-aware": float(np.sqrt(np.mean(acc["time-aware"]))),
                     "time-aware, clustered validation": float(np.sqrt(np.mean(
                         acc["time-aware, clustered validation"]))),
                     "random + best tour": float(np.sqrt(np.mean(rand[n_random])))}
        if "today" not in rows:
            print(f"{robot}: today's campaign failed on every station")
            continue
        base = float(np.mean([r["robot_time"] for r in rows["today"]]))
        print(f"\n{robot.upper()}: {args.seeds} stations, accuracy from {args.draws} noise draws each "
              f"(truth error on {HELD_OUT} held-out poses); robot time by the simulators' own clocks")
        print(f"{'row':<34} {'poses':>6} {'truth RMS':>10} {'vs today':>9} {'robot time':>11} {'ratio':>6} "
              f"{'moves':>7} {'measuring':>9} {'settle':>7} {'sim clock':>9} {'sim val/truth µm':>17} "
              f"{'measured':>8}")
        for name, rs in rows.items():
            t = float(np.mean([r["robot_time"] for r in rs]))
            if name.startswith("physical limit"):
                print(f"{name:<34} {'':>6} {'':>10} {'':>9} {t:>10.1f}s {t / base:>6.2f}")
                continue
            tr = truth_rms[name]
            print(f"{name:<34} {np.mean([r['poses'] for r in rs]):>6.1f} {tr * 1e6:>8.1f}µm "
                  f"{tr / today_rms:>9.3f} "
                  f"{t:>10.1f}s {t / base:>6.2f} {np.mean([r['moves'] for r in rs]):>7.1f} "
                  f"{np.mean([r['measuring'] for r in rs]):>9.1f} {np.mean([r['settle'] for r in rs]):>7.1f} "
                  f"{np.mean([r['sim_clock'] for r in rs]):>9.0f} "
                  f"{np.mean([r['validation_rms'] for r in rs]) * 1e6:>8.1f}/"
                  f"{np.sqrt(np.mean([r['truth_rms'] ** 2 for r in rs])) * 1e6:<8.1f} "
                  f"{np.mean([r['visits'] for r in rs]):>8.1f}")
        for name, seeds in failed.items():
            print(f"{name}: the campaign failed on station(s) {seeds} (not in the means above)")
        today_s, timed_s = (np.mean([s[k] for s in stations]) for k in ("today_seconds", "timed_seconds"))
        print(f"random poses needed for today's accuracy: {n_random}; selection compute per station "
              f"(wall, before the first move): today {today_s:.1f} s, time-aware {timed_s:.1f} s")
        report[robot] = {"rows": rows, "truth_rms": truth_rms, "random_count": n_random}
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1, default=float))


if __name__ == "__main__":
    main()
