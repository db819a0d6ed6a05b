"""A 30-pose campaign on the simulated station: where the wall time goes, and the engine's overhead.

The station runs in real time (speed 1) unless --speed is given. Every event goes to the SQLite store
as in production (a critical subscriber: each point committed before the next move). The engine's
overhead is the wall time not spent in the devices (motion, settle, joint reading, measuring) nor in
the plan's own computation (pose selection, identification), as a share of the device time.

With ``--settle fixed|stable`` (both by default) it runs the campaign once per settle mode
(``robot.settle``: a fixed ``settle_time`` wait, or settling on the tracker's evidence) and compares
the settle + joint reading + measuring time per pose visit, in the station's seconds.

Run: python bench/campaign.py [--speed 1] [--poses 30] [--validation 10] [--settle fixed|stable]
     [--no-warmup] [--acceleration A] [--no-overlap]

Each point's store commit runs while the arm travels to the next pose (`hil.campaign.engine`);
``--no-overlap`` commits it before the next move, as before. The table's "events" rows say how
long delivering events (store commits first) took with the arm standing, and how much of it ran
during the motion instead: per pose visit, the latter is the robot time the overlap saves.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from hil.campaign.chooser import campaign_chooser
from hil.campaign.engine import RealClock
from hil.campaign.events import EventBus
from hil.campaign.runner import run_campaign
from hil.station.config import default_config
from hil.station.devices import open_devices
from hil.store import Store
from mocks.station import start_station


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speed", type=float, default=1.0)
    ap.add_argument("--poses", type=int, default=30)
    ap.add_argument("--validation", type=int, default=10)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--settle", choices=("fixed", "stable"), action="append",
                    help="robot.settle mode(s) to run (default: both, compared)")
    ap.add_argument("--no-warmup", action="store_true", help="warmup.enabled = false")
    ap.add_argument("--acceleration", type=float, default=None, help="robot.acceleration (rad/s²)")
    ap.add_argument("--no-overlap", action="store_true", help="commit each point before the next move")
    args = ap.parse_args()
    per_visit = {}
    for mode in args.settle or ["fixed", "stable"]:
        per_visit[mode] = run(args, mode)
    if len(per_visit) > 1:
        print("\nsettle + joints + measure per pose visit (station seconds):")
        for mode, (seconds, visits, retries) in per_visit.items():
            print(f"  {mode:<7} {seconds / max(visits, 1):6.3f} s over {visits} visits ({retries} retries)")


def run(args: argparse.Namespace, mode: str) -> tuple[float, int, int]:
    """One campaign in settle mode `mode`; prints its table, returns (settle+joints+measure station
    seconds, pose visits, retries)."""
    sim = start_station(speed=args.speed, seed=args.seed)
    try:
        svc = sim.info["services"][0]
        extra = {"robot__acceleration": args.acceleration} if args.acceleration else {}
        config = default_config().with_overrides(
            robot__address=sim.address, tracker__url=svc["tracker_url"], campaign__seed=args.seed,
            campaign__calibration_poses=args.poses, campaign__validation_poses=args.validation,
            robot__settle=mode, warmup__enabled=not args.no_warmup, **extra)
        with tempfile.TemporaryDirectory() as tmp, Store.open(Path(tmp) / "bench.db") as store:
            campaign = store.create_campaign(config, "ur5e")
            bus = EventBus()
            bus.subscribe(store.as_subscriber(), critical=True)
            t0 = time.perf_counter()
            outcome = run_campaign(config, campaign_chooser(config), bus=bus, campaign=campaign,
                                   clock=RealClock(args.speed), devices=open_devices(config),
                                   engine_ready=lambda eng: setattr(eng, "overlap", not args.no_overlap))
            wall = time.perf_counter() - t0
    finally:
        sim.stop()
    t = outcome.timing
    devices = t["motion"] + t["settle"] + t["joints"] + t["measure"]
    engine = t["total"] - devices - t["compute"] - t["suspended"]
    print(f"\nsimulated UR5e at speed {args.speed:g}, settle {mode}: {args.poses} calibration + "
          f"{args.validation} validation poses (+ bootstrap), status {outcome.status}")
    print(f"{'part':<28} {'seconds':>9} {'share':>7}")
    print("-" * 46)
    for name, key in (("motion", "motion"), ("settle", "settle"), ("joint reading", "joints"),
                      ("tracker measurement", "measure"), ("compute (select, identify)", "compute"),
                      ("suspended", "suspended")):
        print(f"{name:<28} {t[key]:>9.2f} {100 * t[key] / t['total']:>6.1f}%")
    print(f"{'engine overhead':<28} {engine:>9.3f} {100 * engine / t['total']:>6.1f}%")
    print(f"{'  of it: events, arm still':<28} {t['events']:>9.3f} {100 * t['events'] / t['total']:>6.1f}%")
    print(f"{'events during motion':<28} {t['events_in_motion']:>9.3f} "
          f"{100 * t['events_in_motion'] / t['total']:>6.1f}%  (inside motion)")
    print(f"{'engine run total':<28} {t['total']:>9.2f}")
    print(f"{'wall incl. connect/close':<28} {wall:>9.2f}")
    print(f"\nengine overhead / device time = {100 * engine / devices:.2f}% (target < 5%)")
    if outcome.result is not None:
        print(f"validation RMS {outcome.result.after.rms * 1e3:.4f} mm "
              f"(before calibration {outcome.result.before.rms * 1e3:.3f} mm)")
    visits = len(outcome.result.records) if outcome.result is not None else 0
    if visits:
        print(f"per pose visit: events with the arm still {1e3 * t['events'] / visits:.1f} ms, during the "
              f"next move {1e3 * t['events_in_motion'] / visits:.1f} ms (wall; the robot time saved at "
              f"speed 1)")
    station = (t["settle"] + t["joints"] + t["measure"]) * args.speed  # the engine's times are wall seconds
    return station, visits, int(t["retries"])


if __name__ == "__main__":
    main()
