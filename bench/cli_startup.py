"""Start-up time of the command line: how long a command takes before it does anything.

    python bench/cli_startup.py [--runs 7] [--source DIR]

Runs each command `--runs` times in a fresh interpreter (stdout and stderr discarded) and prints a table of
the median and the fastest wall time, next to ``python -c pass`` (the interpreter's own start, the floor
no command can go below). Target: ``hil --help`` under 0.3 s. ``--source DIR`` times another checkout of
hil (e.g. ``git archive HEAD | tar -x -C /tmp/old``) through PYTHONPATH, for a before/after comparison.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

COMMANDS: tuple[tuple[str, list[str]], ...] = (
    ("python -c pass", ["-c", "pass"]),
    ("hil --help", ["-m", "hil", "--help"]),
    ("hil history --help", ["-m", "hil", "history", "--help"]),
    ("hil select --help", ["-m", "hil", "select", "--help"]),
)


def timed(argv: list[str], env: dict[str, str], cwd: Path, runs: int) -> list[float]:
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, *argv], env=env, cwd=cwd, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, check=False)
        times.append(time.perf_counter() - t0)
    return times


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=7, help="runs per command (default: 7)")
    ap.add_argument("--source", type=Path, help="time the hil found in this directory instead")
    args = ap.parse_args()
    env = dict(os.environ)
    if args.source:
        env["PYTHONPATH"] = str(args.source.resolve()) + os.pathsep + env.get("PYTHONPATH", "")
    where = args.source or ROOT
    print(f"hil from {where}; {args.runs} runs each; {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.2f}")
    print(f"{'command':<22} {'median [s]':>10} {'fastest [s]':>11}")
    for name, argv in COMMANDS:
        t = timed(argv, env, where, args.runs)
        print(f"{name:<22} {statistics.median(t):>10.3f} {min(t):>11.3f}")


if __name__ == "__main__":
    main()
