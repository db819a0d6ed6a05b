"""A 30-pose campaign on the simulated station: where the wall time goes, and the engine's overhead.

The station runs in real time (speed 1) unless --speed is given. Every event goes to the SQLite store
as in production (a critical subscriber: each point committed before the next move). The engine's
overhead is the wall time not spent in the devices (motion, settle, joint reading, measuring) nor in
the plan's own computation (pose selection, identification), as a share of the device time.

Run: python bench/campaign.py [--speed 1] [--poses 30] [--validation 10]
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
from hil.store import Store
from mocks.station import start_station


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speed", type=float, default=1.0)
    ap.add_argument("--poses", type=int, default=30)
    ap.add_argument("--validation", type=int, default=10)
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args()
    sim = start_station(speed=args.speed, seed=args.seed)
    try:
        svc = sim.info["services"][0]
        config = default_config().with_overrides(
            robot__address=sim.address, tracker__url=svc["tracker_url"], campaign__seed=args.seed,
            campaign__calibration_poses=args.poses, campaign__validation_poses=args.validation)
        with tempfile.TemporaryDirectory() as tmp, Store.open(Path(tmp) / "bench.db") as store:
            campaign = store.create_campaign(config, "ur5e")
            bus = EventBus()
            bus.subscribe(store.as_subscriber(), critical=True)
            t0 = time.perf_counter()
            outcome = run_campaign(config, campaign_chooser(config), bus=bus, campaign=campaign,
                                   clock=RealClock(args.speed))
            wall = time.perf_counter() - t0
    finally:
        sim.stop()
    t = outcome.timing
    devices = t["motion"] + t["settle"] + t["joints"] + t["measure"]
    engine = t["total"] - devices - t["compute"] - t["suspended"]
    print(f"simulated UR5e at speed {args.speed:g}: {args.poses} calibration + {args.validation} "
          f"validation poses (+ bootstrap), status {outcome.status}")
    print(f"{'part':<28} {'seconds':>9} {'share':>7}")
    print("-" * 46)
    for name, key in (("motion", "motion"), ("settle", "settle"), ("joint reading", "joints"),
                      ("tracker measurement", "measure"), ("compute (select, identify)", "compute"),
                      ("suspended", "suspended")):
        print(f"{name:<28} {t[key]:>9.2f} {100 * t[key] / t['total']:>6.1f}%")
    print(f"{'engine overhead':<28} {engine:>9.3f} {100 * engine / t['total']:>6.1f}%")
    print(f"{'engine run total':<28} {t['total']:>9.2f}")
    print(f"{'wall incl. connect/close':<28} {wall:>9.2f}")
    print(f"\nengine overhead / device time = {100 * engine / devices:.2f}% (target < 5%)")
    if outcome.result is not None:
        print(f"validation RMS {outcome.result.after.rms * 1e3:.4f} mm "
              f"(before calibration {outcome.result.before.rms * 1e3:.3f} mm)")


if __name__ == "__main__":
    main()
