"""N simulated stations calibrating at once into one PostgreSQL database: every row accounted for.

Each station is a real `hil calibrate --sim` process (its own simulated UR arm with its own serial and
hidden errors, its own simulated tracker, driven through ur_rtde and GeoCOM), all writing to one
PostgreSQL 15 server on loopback (durable settings, started here by initdb in a temporary folder,
tests/pg_server.py). Optionally the server is restarted while they run (``--restart-after S``): every
station must wait and continue.

Afterwards, per campaign: finished (accepted or rejected), every planned pose measured or skipped with a
reason, no pose measured twice, the event log numbered 1..n without a gap, and the lease released; and
`hil robots` lists the N robots. The table prints wall time per station and these checks.

Run: python bench/fleet_stations.py [--stations 4] [--speed 50] [--poses 10] [--validation 4]
     [--restart-after 20]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import threading
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from hil.store import Store  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stations", type=int, default=4)
    ap.add_argument("--speed", type=float, default=50.0)
    ap.add_argument("--poses", type=int, default=10)
    ap.add_argument("--validation", type=int, default=4)
    ap.add_argument("--restart-after", type=float, default=None, metavar="S",
                    help="stop the database S seconds after the start and start it again 3 s later")
    args = ap.parse_args()
    from tests.pg_server import PostgresServer

    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    with PostgresServer(fast=False) as pg:
        url = pg.create_database("fleet")
        started = time.perf_counter()
        procs = []
        for k in range(args.stations):
            cmd = [sys.executable, "-m", "hil", "calibrate", "--sim", "--seed", str(k + 1), "--speed",
                   str(args.speed), "--poses", str(args.poses), "--validation", str(args.validation),
                   "--db", url]
            procs.append(subprocess.Popen(cmd, cwd=ROOT, env=env, stdin=subprocess.DEVNULL,
                                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True))
        restart = None
        if args.restart_after is not None:
            def bounce() -> None:
                pg.stop()
                time.sleep(3.0)
                pg.start()

            restart = threading.Timer(args.restart_after, bounce)
            restart.start()
        results = []
        for p in procs:
            _, err = p.communicate(timeout=1800)
            results.append((p.returncode, time.perf_counter() - started, err))
        if restart is not None:
            restart.join()
        with Store.open(url, readonly=True) as store:
            campaigns = store.campaigns(limit=None)
            rows = []
            for c in sorted(campaigns, key=lambda c: c.serial):
                counts = Counter(m.index for m in store.measurements(c.id))
                seqs = [s for s, _ in store.event_log(c.id)]
                skipped = [p for p in store.poses(c.id) if p.status == "skipped"]
                rows.append((c, max(counts.values()) == 1, seqs == list(range(1, len(seqs) + 1)),
                             all(p.reason for p in skipped)))
            leases = store.leases()
        robots = subprocess.run([sys.executable, "-m", "hil", "robots", "--db", url, "--json"], cwd=ROOT,
                                env=env, capture_output=True, text=True, timeout=120)
    waited = sum("database link lost" in err for _, _, err in results)
    print(f"{args.stations} simulated stations, one PostgreSQL database"
          + (f", restarted at {args.restart_after:g} s" if args.restart_after is not None else ""))
    print(f"{'robot':<12} {'status':<9} {'planned':>7} {'measured':>8} {'skipped':>7} {'once':>5} "
          f"{'gapless':>7} {'reasons':>7}")
    for c, once, gapless, reasons in rows:
        print(f"{c.serial:<12} {c.status:<9} {c.planned:>7} {c.measured:>8} {c.skipped:>7} "
              f"{'yes' if once else 'NO':>5} {'yes' if gapless else 'NO':>7} {'yes' if reasons else 'NO':>7}")
    codes = [code for code, _, _ in results]
    print(f"exit codes {codes}; wall {max(t for _, t, _ in results):.1f} s; stations that waited for the "
          f"database: {waited}; leases left: {len(leases)}")
    listed = json.loads(robots.stdout)["robots"] if robots.returncode == 0 else []
    accounted = (len(rows) == args.stations and all(o and g and r for _, o, g, r in rows)
                 and all(c.measured + c.skipped == c.planned for c, *_ in rows) and not leases
                 and len(listed) == args.stations)
    print(f"`hil robots` lists {len(listed)} robots; every row accounted for: {'yes' if accounted else 'NO'}")
    if not accounted:
        for code, _, err in results:
            if code not in (0, 1):
                print(err[-800:], file=sys.stderr)


if __name__ == "__main__":
    main()
