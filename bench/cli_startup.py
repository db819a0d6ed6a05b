"""Wall time of the command line: how long a command takes before it does anything, and the commands
that should take no longer than that — the listings and an identification.

    python bench/cli_startup.py [--runs 7] [--source DIR]

Runs each command `--runs` times in a fresh interpreter (stdout and stderr discarded) and prints a table
of the median and the fastest wall time and the median as a multiple of ``hil --help``'s in the same
run (the ratio is what compares across machines and loads) and the median CPU time (user + system:
what the wall time is on an idle machine, give or take the disk), next to ``python -c pass`` (the
interpreter's own start, the floor no command can go below). Targets on an idle machine: ``hil --help``
under 0.3 s; a listing (``hil history``, ``hil show``, ``hil robots``, ``hil robot``) and ``hil
identify`` of 40 poses under 0.5 s.

The listings read a store made for the run (SQLite, in a temporary folder: 3 robots calibrated 4 times
each, every campaign with its model document and validation, 5 poses measured); ``hil identify`` fits
40 synthetic measurements of a random UR5e. ``--source DIR`` times another checkout of hil (e.g. ``git
archive HEAD | tar -x -C /tmp/old``) through PYTHONPATH on the same files, for a before/after
comparison.

Two rows are floors rather than commands: ``import sqlalchemy`` (what a listing paid before it read
anything, until a station's SQLite file was read with sqlite3 alone: `hil.store.sqlite_reader`; a
PostgreSQL store still pays it) and ``import numpy, pinocchio`` (what ``hil identify`` pays before it
fits).

Python's bytecode cache: a command run the second time reads its modules' compiled bytecode instead of
compiling their source, as an installed hil always does (pip compiles on install). With
PYTHONDONTWRITEBYTECODE set and a source checkout, every run compiles all of hil's modules it imports
again: compiling the 33 modules of hil ``hil history`` imports took 40 ms of CPU, the 42 of ``hil
identify`` 73 ms (a loaded 2-core machine, where ``hil --help`` took twice its idle CPU time). So by
default each command runs once untimed with the bytecode written to a folder of the run
(PYTHONPYCACHEPREFIX, nothing written into the checkout) and is then timed reading it;
``--no-bytecode`` times compiling every run instead.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

SERIAL = "20235500101"
ROBOTS = {SERIAL: "ur5e", "20235500202": "ur5e", "20235500303": "ur10e"}


def make_inputs(folder: Path) -> tuple[Path, Path]:
    """(a store of a small fleet, a measurements CSV of 40 poses) in `folder`."""
    import numpy as np

    from hil.calibration.identification import identify, validate
    from hil.calibration.measurements import Measurements, write_measurements
    from hil.calibration.model_file import model_document
    from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
    from hil.campaign.events import PointMeasured, RunStarted
    from hil.station.config import default_config
    from hil.store import RobotIdentity, Store

    rng = np.random.default_rng(1)
    csv = folder / "measurements.csv"
    truth = random_truth("ur5e", rng)
    q, p = measure(truth, random_configurations("ur5e", 40, rng), Noise(), rng)
    write_measurements(csv, q, p)
    store = folder / "hil.db"
    with Store.open(store) as s:
        for r, (serial, robot) in enumerate(ROBOTS.items()):
            arm = random_truth(robot, rng, rigid=True)
            q_cal, p_cal = measure(arm, random_configurations(robot, 30, rng), Noise(), rng)
            q_val, p_val = measure(arm, random_configurations(robot, 12, rng), Noise(), rng)
            fit = identify(Measurements.from_arrays(q_cal, p_cal), robot)
            held_out = Measurements.from_arrays(q_val, p_val)
            before, after = validate(fit.baseline, held_out), validate(fit.geometry, held_out)
            config = default_config().as_dict()
            config["robot"]["type"] = robot
            config["station"]["name"] = f"eol-cell-{r % 2 + 1}"
            for k in range(4):
                cid = s.create_campaign(config, RobotIdentity(robot, serial, robot.upper(), "5.15.0"),
                                        {"method": "tabu"}, now=1.7e9 + k * 86400.0 * 30 + r * 3600.0)
                s.save_plan(cid, [(i, "calibration", q_cal[i]) for i in range(5)])
                s.record_event(RunStarted(campaign=cid, robot=robot, station=config["station"]["name"],
                                          poses=5))
                for i in range(5):
                    s.record_event(PointMeasured(campaign=cid, index=i, role="calibration", q=q_cal[i],
                                                 p=p_cal[i], p_spread=[0.0] * 3, samples=5))
                s.save_model(cid, model_document(fit, after.as_dict()))
                s.save_validation(cid, before.as_dict(), after.as_dict(), True)
                s.set_status(cid, "accepted")
    return store, csv


def commands(store: Path, csv: Path, out: Path) -> tuple[tuple[str, list[str]], ...]:
    db = ["--db", str(store)]
    return (
        ("python -c pass", ["-c", "pass"]),
        ("import sqlalchemy", ["-c", "import sqlalchemy"]),
        ("import numpy, pinocchio", ["-c", "import numpy, pinocchio"]),
        ("hil --help", ["-m", "hil", "--help"]),
        ("hil history --help", ["-m", "hil", "history", "--help"]),
        ("hil select --help", ["-m", "hil", "select", "--help"]),
        ("hil history", ["-m", "hil", "history", *db]),
        ("hil show last", ["-m", "hil", "show", "last", *db]),
        ("hil robots", ["-m", "hil", "robots", *db]),
        ("hil robot SERIAL", ["-m", "hil", "robot", SERIAL, *db]),
        ("hil identify (40 poses)", ["-m", "hil", "identify", "--robot", "ur5e", "--measurements", str(csv),
                                     "--out", str(out)]),
    )


def timed(argv: list[str], env: dict[str, str], cwd: Path, runs: int) -> tuple[list[float], list[float]]:
    """(wall times, CPU times: user + system) of `runs` runs of ``python ARGV``."""
    times, cpu = [], []
    for _ in range(runs):
        r0, t0 = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
        done = subprocess.run([sys.executable, *argv], env=env, cwd=cwd, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, check=False)
        times.append(time.perf_counter() - t0)
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu.append(r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime)
        if done.returncode != 0:
            sys.exit(f"{' '.join(argv)}: exit {done.returncode}: {done.stderr.decode()[-500:]}")
    return times, cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=7, help="runs per command (default: 7)")
    ap.add_argument("--source", type=Path, help="time the hil found in this directory instead")
    ap.add_argument("--no-bytecode", action="store_true",
                    help="compile every module's source on every run (PYTHONDONTWRITEBYTECODE)")
    args = ap.parse_args()
    env = dict(os.environ)
    env.pop("HIL_DB", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env.pop("PYTHONPYCACHEPREFIX", None)
    if args.source:
        env["PYTHONPATH"] = str(args.source.resolve()) + os.pathsep + env.get("PYTHONPATH", "")
    where = args.source or ROOT
    with tempfile.TemporaryDirectory(prefix="hil-cli-startup-") as tmp:
        folder = Path(tmp)
        env["XDG_DATA_HOME"] = str(folder / "data")  # nothing of the user's
        if args.no_bytecode:
            env["PYTHONDONTWRITEBYTECODE"] = "1"
        else:
            env["PYTHONPYCACHEPREFIX"] = str(folder / "pycache")  # the run's, not the checkout's
        store, csv = make_inputs(folder)
        cache = "compiled every run" if args.no_bytecode else "bytecode cached (one untimed run first)"
        print(f"hil from {where}; {args.runs} runs each; {cache}; {os.cpu_count()} cores, "
              f"load average {os.getloadavg()[0]:.2f}")
        print(f"{'command':<24} {'median [s]':>10} {'fastest [s]':>11} {'× hil --help':>12} "
              f"{'CPU [s]':>8}")
        baseline = None
        for name, argv in commands(store, csv, folder / "model.json"):
            if not args.no_bytecode:
                timed(argv, env, where, 1)  # writes the bytecode the timed runs read
            times, cpu = timed(argv, env, where, args.runs)
            t = statistics.median(times)
            baseline = t if name == "hil --help" else baseline
            ratio = f"{t / baseline:>12.2f}" if baseline else f"{'':>12}"
            print(f"{name:<24} {t:>10.3f} {min(times):>11.3f} {ratio} {statistics.median(cpu):>8.3f}")


if __name__ == "__main__":
    main()
