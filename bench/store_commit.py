"""The measurement commit on SQLite and PostgreSQL: latency of one commit and throughput, one writer and
several writers at once.

What is timed is what the campaign engine does after each measured point, before the next move: one
`Store.record_event(PointMeasured)`, a transaction appending the event and the measurement and marking
the pose (plus the PoseStarted that precedes it). Durable settings on both engines: SQLite in WAL with
synchronous=FULL (an fsync per commit), PostgreSQL 15 on loopback with fsync and synchronous_commit on
(its defaults), started here by initdb in a temporary folder (tests/pg_server.py). Several writers are
separate processes, each a station with its own campaign, all on the same database.

The ratio column compares each row with SQLite, one writer, in the same run. A pose takes seconds to
reach and measure, so the budget per commit is tens of milliseconds.

Run: python bench/store_commit.py [--points 300] [--writers 4]
"""

from __future__ import annotations

import argparse
import multiprocessing
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hil.campaign.events import PointMeasured, PoseStarted  # noqa: E402
from hil.station.config import default_config  # noqa: E402
from hil.store import RobotIdentity, Store  # noqa: E402


def _station(location: str, name: str, points: int, start: multiprocessing.synchronize.Event | None,
             out: multiprocessing.queues.Queue | None = None) -> list[float]:
    """One station: a campaign of `points` measured points; returns each commit's latency (s)."""
    config = default_config().as_dict()
    config["station"]["name"] = name
    latencies = []
    with Store.open(location) as store:
        lease = store.claim_new(config, RobotIdentity("ur5e", f"bench-{name}"), heartbeat=False)
        cid = lease.campaign
        if start is not None:
            start.wait(60)
        for i in range(points):
            q = [0.001 * i, -1.2, 1.1, 0.1, 0.5, 0.0]
            store.record_event(PoseStarted(campaign=cid, index=i, role="calibration", target=q))
            t0 = time.perf_counter()
            store.record_event(PointMeasured(campaign=cid, index=i, role="calibration", q=q,
                                             p=[1.0, 2.0, 0.001 * i], p_spread=[1e-6] * 3, samples=5))
            latencies.append(time.perf_counter() - t0)
        lease.release()
    if out is not None:
        out.put(latencies)
    return latencies


def _run(location: str, writers: int, points: int) -> tuple[list[float], float]:
    """(every commit's latency, wall seconds) with `writers` stations writing at once."""
    if writers == 1:
        t0 = time.perf_counter()
        lat = _station(location, "w0", points, None)
        return lat, time.perf_counter() - t0
    ctx = multiprocessing.get_context("spawn")
    start, out = ctx.Event(), ctx.Queue()
    procs = [ctx.Process(target=_station, args=(location, f"w{k}", points, start, out))
             for k in range(writers)]
    for p in procs:
        p.start()
    time.sleep(3.0)  # every station opened and claimed its campaign
    t0 = time.perf_counter()
    start.set()
    lat = []
    for _ in procs:
        lat += out.get(timeout=600)
    wall = time.perf_counter() - t0
    for p in procs:
        p.join(60)
    return lat, wall


def _check(location: str, writers: int, points: int) -> str:
    """Every row accounted for: `writers` campaigns of `points` measurements, events without gaps."""
    with Store.open(location, readonly=True) as store:
        campaigns = store.campaigns(limit=None)
        ok = len(campaigns) == writers
        for c in campaigns:
            log = store.event_log(c.id)
            ok &= c.measured == points and len(store.measurements(c.id)) == points
            ok &= [s for s, _ in log] == list(range(1, 2 * points + 1))
    return "yes" if ok else "NO"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=300, help="measured points per station")
    ap.add_argument("--writers", type=int, default=4, help="stations writing at once (second row)")
    args = ap.parse_args()
    from tests.pg_server import PostgresServer

    rows = []
    with tempfile.TemporaryDirectory() as tmp, PostgresServer(fast=False) as pg:  # started
        for engine in ("sqlite", "postgresql"):
            for writers in (1, args.writers):
                name = f"{engine}_{writers}"
                location = str(Path(tmp) / f"{name}.db") if engine == "sqlite" else pg.create_database(name)
                lat, wall = _run(location, writers, args.points)
                lat_ms = sorted(x * 1e3 for x in lat)
                rows.append((engine, writers, statistics.median(lat_ms), lat_ms[int(0.95 * len(lat_ms))],
                             lat_ms[-1], len(lat) / wall, _check(location, writers, args.points)))
    base = rows[0][5]
    print(f"measurement commit ({args.points} points per station; durable settings on both engines)")
    print(f"{'engine':<11} {'stations':>8} {'median ms':>10} {'p95 ms':>8} {'max ms':>8} "
          f"{'points/s':>10} {'vs SQLite×1':>12} {'all rows':>9}")
    for engine, writers, med, p95, worst, rate, ok in rows:
        print(f"{engine:<11} {writers:>8} {med:>10.2f} {p95:>8.2f} {worst:>8.2f} {rate:>10.0f} "
              f"{rate / base:>11.2f}x {ok:>9}")


if __name__ == "__main__":
    main()
