"""How long the fleet views take on a large plant: ``hil robots``' listing, one robot's history, and the
fleet report's data.

    python bench/fleet.py [--robots 200] [--calibrations 50] [--stations 4] [--db PATH|URL]
                          [--runs 5] [--report fleet.html]

Fills a new store (a temporary SQLite file, or ``--db``: a file or an empty ``postgresql://`` database)
with `--robots` robots of `--calibrations` calibrations each, spread over `--stations` stations, each
with a full-size model document (a real identification's, about 22 kB) and a validation, about one in
ten rejected and one in fifty marked bad; then prints the median and fastest of `--runs` calls of each
query. The target: the fleet listing of 200 robots x 50 calibrations in well under a second on SQLite.
``--report`` also writes the fleet report of that store (its figures with many robots).

The rows are written in one transaction with SQLAlchemy Core against `hil.store.tables` (the Store's
own methods commit, and sync, one row at a time: minutes for 10 000 campaigns).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from sqlalchemy import insert

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hil.calibration.identification import identify  # noqa: E402
from hil.calibration.measurements import Measurements  # noqa: E402
from hil.calibration.model_file import model_document  # noqa: E402
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth  # noqa: E402
from hil.store import Store  # noqa: E402
from hil.store import tables as tb  # noqa: E402
from hil.store.fleet import calibrations, fleet, robot_history  # noqa: E402

DAY = 86400.0


def model_text(rng: np.random.Generator) -> str:
    truth = random_truth("ur5e", rng)
    q, p = measure(truth, random_configurations("ur5e", 30, rng), Noise(), rng)
    return json.dumps(model_document(identify(Measurements.from_arrays(q, p), "ur5e")))


def fill(store: Store, robots: int, per_robot: int, stations: int, rng: np.random.Generator) -> int:
    doc = model_text(rng)
    t0 = time.time() - per_robot * 7 * DAY
    names = [f"eol-cell-{i + 1}" for i in range(stations - 1)] + ["rework-bay-north"]
    with store.writing("fill the benchmark fleet") as conn:
        conn.execute(insert(tb.stations),
                     [{"id": i + 1, "name": n, "created": t0} for i, n in enumerate(names)])
        conn.execute(insert(tb.robots), [
            {"id": r + 1, "serial": f"2024{r:07d}", "type": "ur5e", "model": "UR5e", "software": "5.15",
             "first_seen": t0, "last_seen": t0 + per_robot * 7 * DAY} for r in range(robots)])
        campaigns, models, validations, marks = [], [], [], []
        for r in range(robots):
            quality = rng.lognormal(np.log(35e-6), 0.25)  # some robots calibrate better than others
            for k in range(per_robot):
                cid = f"bench-{r:05d}-{k:03d}"
                created = t0 + k * 7 * DAY + r * 60.0
                after = quality * rng.lognormal(0, 0.15)
                rejected = rng.random() < 0.1
                if rejected:
                    after *= 8
                campaigns.append({"id": cid, "station": int(rng.integers(stations)) + 1, "robot": r + 1,
                                  "robot_type": "ur5e", "config": "{}",
                                  "status": "rejected" if rejected else "accepted", "created": created,
                                  "updated": created})
                mid = len(models) + 1
                models.append({"id": mid, "campaign": cid, "doc": doc, "sha256": f"{mid:064x}",
                               "rms": after * 0.8, "created": created})
                before = rng.lognormal(np.log(2e-3), 0.2)
                validations.append({"campaign": cid, "model": mid, "before": json.dumps(
                    {"count": 12, "rms": before, "max": 2 * before}), "after": json.dumps(
                    {"count": 12, "rms": after, "max": 2 * after}), "passed": int(not rejected), "rms": after,
                    "sha256": f"{mid:064x}", "created": created})
                if rng.random() < 0.02:
                    marks.append({"campaign": cid, "bad": 1, "reason": "benchmark", "who": "bench",
                                  "t": created + DAY})
        for table, rows in ((tb.campaigns, campaigns), (tb.models, models), (tb.validations, validations),
                            (tb.marks, marks)):
            for i in range(0, len(rows), 2000):
                conn.execute(insert(table), rows[i:i + 2000])
    return len(campaigns)


def timed(fn, runs: int) -> tuple[float, float]:
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robots", type=int, default=200, help="robots in the fleet (default: 200)")
    ap.add_argument("--calibrations", type=int, default=50, help="calibrations per robot (default: 50)")
    ap.add_argument("--stations", type=int, default=4, help="stations (default: 4)")
    ap.add_argument("--db", help="an empty store to fill: a new file, or an empty postgresql:// database "
                                 "(default: a temporary SQLite file)")
    ap.add_argument("--runs", type=int, default=5, help="calls of each query (default: 5)")
    ap.add_argument("--report", type=Path, help="also write the fleet report of the filled store here")
    args = ap.parse_args()
    rng = np.random.default_rng(7)
    with tempfile.TemporaryDirectory() as tmp:
        location = args.db or str(Path(tmp) / "fleet.db")
        with Store.open(location) as store:
            t = time.perf_counter()
            n = fill(store, args.robots, args.calibrations, args.stations, rng)
            print(f"{store.location}: {args.robots} robots, {n} calibrations, filled in "
                  f"{time.perf_counter() - t:.1f} s; {args.runs} runs each\n")
            serial = f"2024{args.robots // 2:07d}"
            rows = [
                ("fleet listing (hil robots)", lambda: fleet(store)),
                (f"one robot's history ({args.calibrations} calibrations)",
                 lambda: robot_history(store, serial)),
                ("every calibration (fleet report)", lambda: calibrations(store)),
            ]
            print(f"{'query':<44} {'median':>9} {'fastest':>9}")
            for name, fn in rows:
                median, fastest = timed(fn, args.runs)
                print(f"{name:<44} {median * 1e3:>7.1f}ms {fastest * 1e3:>7.1f}ms")
            if args.report:
                from hil.report.fleet import fleet_data, write_fleet_report

                t = time.perf_counter()
                write_fleet_report(fleet_data(store), args.report)
                print(f"\nwrote {args.report} in {time.perf_counter() - t:.1f} s")


if __name__ == "__main__":
    main()
