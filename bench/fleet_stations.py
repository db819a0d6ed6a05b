"""N simulated stations calibrating at once into one PostgreSQL database: every row accounted for.

Each station is a real `hil calibrate --sim` process (its own simulated UR arm with its own serial and
hidden errors, its own simulated tracker, driven through ur_rtde and GeoCOM), all writing to one
PostgreSQL 15 server on loopback (durable settings, started here by initdb in a temporary folder,
tests/pg_server.py). Optionally the server is stopped for a few seconds once every station is
measuring (``--restart``): every station must wait and continue. Stations start 5 s apart, as cells do.

Afterwards, per campaign: finished (accepted or rejected), every planned pose measured or skipped with a
reason, no pose measured twice, the event log numbered 1..n without a gap, and the lease released; and
`hil robots` lists the N robots. The table prints wall time per station and these checks.

Run: python bench/fleet_stations.py [--stations 4] [--speed 50] [--poses 10] [--validation 4]
     [--restart] [--down 5]
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
    ap.add_argument("--restart", action="store_true",
                    help="stop the database once every station has measured 2 points, start it again later")
    ap.add_argument("--down", type=float, default=5.0, metavar="S", help="seconds the database is down")
    args = ap.parse_args()
    from tests.pg_server import PostgresServer

    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    with PostgresServer(fast=False) as pg:
        url = pg.create_database("fleet")
        started = time.perf_counter()
        procs, lines = [], []
        for k in range(args.stations):
            cmd = [sys.executable, "-m", "hil", "calibrate", "--sim", "--seed", str(k + 1), "--speed",
                   str(args.speed), "--poses", str(args.poses), "--validation", str(args.validation),
                   "--db", url]
            proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdin=subprocess.DEVNULL,
                                    stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            out: list[str] = []
            threading.Thread(target=lambda p=proc, o=out: o.extend(iter(p.stderr.readline, "")),
                             daemon=True).start()
            procs.append(proc)
            lines.append(out)
            time.sleep(5.0)
        bounced_at = None
        if args.restart:
            deadline = time.monotonic() + 900
            while time.monotonic() < deadline and not all(
                    sum("measured pose" in ln for ln in out) >= 2 for out in lines):
                if all(p.poll() is not None for p in procs):
                    break
                time.sleep(0.2)
            bounced_at = time.perf_counter() - started
            pg.stop()
            time.sleep(args.down)
            pg.start()
        results = []
        for p, out in zip(procs, lines, strict=True):
            p.wait(timeout=1800)
            time.sleep(0.2)  # the reader thread takes the last lines
            results.append((p.returncode, time.perf_counter() - started, "".join(out)))
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
          + (f", down {args.down:g} s from {bounced_at:.1f} s (all stations measuring)"
             if bounced_at is not None else ""))
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
