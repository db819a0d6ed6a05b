"""The adversarial pass, as figures: bad inputs over every subcommand, and faults injected into campaigns.

    python bench/adversarial.py [--faults 10] [--seed 1] [--only calibrate,select] [--no-faults]
                                [--no-sweep] [--classes] [--station] [--verbose]

1. **Bad inputs.** Runs the table of tests/hil/cli/bad_input_cases.py (the one
   tests/hil/cli/test_bad_input_sweep.py runs) in this process, each case with a time limit, and prints
   per subcommand: cases, how many meet the error contract (exit 2, one line naming the option/file/key,
   no traceback, nothing written, created or started), and the ids of those that fail; then per class
   of bad input and bad surroundings (case ids ``c1-`` … ``c6-``: inputs that never end, outputs that
   go nowhere, numbers that are not physical, a config checked before any connection, a damaged store
   row, odd environments) the cases, how many meet the contract and the longest time one took to be
   refused (target: under 2 s); then each case that connects to the simulated station (a robot type
   the controller contradicts, ``--station`` runs only those) with its time to be refused, cold and
   warm.
2. **Faults.** Runs ``hil calibrate --sim --speed 50`` (a small campaign) in a subprocess and interrupts
   it at seeded random moments — SIGKILL of the process (``kill -9``), SIGINT to its process group
   (Ctrl-C) or SIGTERM (``kill``), a random number of measured points into the run plus a random
   fraction of a second — then re-runs the same command until the campaign finishes. A fault *resumed
   exactly* when the next run continued the same campaign, measured no pose again (the store holds one
   measurement per pose, and those taken before the fault are untouched), kept the plan (no planned
   pose's target changed, the bootstrap's included), and the finished campaign has every planned pose
   measured or skipped with a reason, as many calibration and validation poses as asked. An
   uninterrupted run is checked the same way first, so a failing check is the product's, not the
   bench's. Processes left behind by a ``kill -9`` (ur_rtde's client, the simulator) are counted.

Prints both tables and a total line each; exit code 0 when everything met the contract and resumed
exactly, 1 otherwise.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import random
import shutil
import signal
import sqlite3
import subprocess
import sys
import tempfile
import threading
import time
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


# ------------------------------------------------------------------------------------------ bad inputs

def sweep(only: set[str] | None, verbose: bool, classes_only: bool = False,
          station_only: bool = False) -> tuple[int, int]:
    """Run the bad-input table; print the per-subcommand table; return (cases, meeting the contract).
    `classes_only`: only the cases of the classes (`CLASSES`); `station_only`: only the cases that
    connect to the simulated station (`Case.station`)."""
    from tests.hil.cli.bad_input_cases import CASES, Outcome, build_fixtures, run_case, start_sim_station

    cases = [c for c in CASES if (only is None or c.cmd in only)
             and (not classes_only or c.id.split("-", 1)[0] in CLASSES)
             and (not station_only or c.station)]
    work = Path(tempfile.mkdtemp(prefix="hil-adversarial-"))
    station = None
    no_station = ""
    results: list[Outcome] = []
    try:
        fixtures = build_fixtures(work / "fixtures")
        t0 = time.monotonic()
        for i, case in enumerate(cases):
            if case.station and station is None:
                for _attempt in range(2):  # a loaded machine may be slow to start it
                    try:
                        station = start_sim_station()
                        break
                    except Exception as exc:
                        no_station = f"the simulated station did not start: {exc}"
            if case.station and station is None:
                results.append(Outcome(case, None, "", [no_station], 0.0))
                continue
            outcome = run_case(case, fixtures, work / f"case-{i}", station=station, timeout=case.timeout)
            results.append(outcome)
            shutil.rmtree(work / f"case-{i}", ignore_errors=True)
            if case.id.split("-", 1)[0] in CLASSES or case.station:  # again, its libraries loaded
                again = run_case(case, fixtures, work / f"case-{i}-warm", station=station,
                                 timeout=case.timeout)
                WARM[case.name] = again.seconds if again.ok else float("inf")
                shutil.rmtree(work / f"case-{i}-warm", ignore_errors=True)
            if sys.stderr.isatty():
                print(f"\r{i + 1}/{len(cases)} cases", end="", file=sys.stderr, flush=True)
        print(f"\r{len(cases)} cases in {time.monotonic() - t0:.0f} s", file=sys.stderr)
    finally:
        if station is not None:
            station.stop()
        shutil.rmtree(work, ignore_errors=True)

    by_cmd: dict[str, list[Any]] = defaultdict(list)
    for r in results:
        by_cmd[r.case.cmd].append(r)
    print("\nBad inputs: exit 2, one line naming the option/file/key, no traceback, nothing written, "
          "created, started or moved")
    print(f"{'subcommand':<12} {'cases':>5} {'meet':>5} {'fail':>5}  failing case ids")
    for cmd, rs in by_cmd.items():
        failing = [r for r in rs if not r.ok]
        print(f"{cmd:<12} {len(rs):>5} {len(rs) - len(failing):>5} {len(failing):>5}  "
              + ", ".join(r.case.id for r in failing))
    total_fail = sum(1 for r in results if not r.ok)
    print(f"{'total':<12} {len(results):>5} {len(results) - total_fail:>5} {total_fail:>5}")
    by_class(results)
    by_station(results)
    if verbose and total_fail:
        print("\nFailing cases:")
        for r in results:
            if not r.ok:
                print(f"  {r.case.name}: {'; '.join(r.problems)}")
                if r.err:
                    print(f"      stderr: {r.err.splitlines()[-1][:240]}")
    return len(results), len(results) - total_fail


#: The classes of bad input and bad surroundings (the table's case ids begin "c<n>-").
CLASSES = {"c1": "inputs that never end", "c2": "outputs that go nowhere",
           "c3": "numbers that are not physical", "c4": "config before connection",
           "c5": "a damaged store row", "c6": "odd environments, ambiguous kinds"}


#: case name -> seconds of its second run (the command's libraries already imported): a class case
#: runs twice, so the time to refuse is told apart from the first import of numpy, scipy, pinocchio.
WARM: dict[str, float] = {}


def by_class(results: list[Any]) -> None:
    """Per class: cases, meeting the contract, and the longest time a case took to be
    refused (or, for the cases that must succeed, to finish) — on its first run (cold: the command's
    imports included) and its second (warm: a failing second run counts as infinite); then the longest
    over the whole table."""
    print("\nBy class: cases, meeting the contract, longest time to refuse (cold / warm); "
          "r2: the cases of the second independent pass among them (ids c<n>-r2-...)")
    print(f"{'class':<40} {'cases':>5} {'meet':>5} {'r2':>4} {'r2 meet':>7} {'cold':>8} {'warm':>8}  "
          "slowest warm case")
    for key, words in CLASSES.items():
        rs = [r for r in results if r.case.id.startswith(f"{key}-")]
        if not rs:
            continue
        second = [r for r in rs if r.case.id.startswith(f"{key}-r2-")]
        cold = max(r.seconds for r in rs)
        warm = max(rs, key=lambda r: WARM.get(r.case.name, r.seconds))
        print(f"{key + ' ' + words:<40} {len(rs):>5} {sum(r.ok for r in rs):>5} {len(second):>4} "
              f"{sum(r.ok for r in second):>7} {cold:>7.2f}s "
              f"{WARM.get(warm.case.name, warm.seconds):>7.2f}s  {warm.case.name}")
    refused = [r for r in results if r.case.expect == 2]
    if refused:
        slowest = max(refused, key=lambda r: r.seconds)
        met = sum(r.ok for r in refused)
        print(f"{'every bad input of the table (cold)':<40} {len(refused):>5} {met:>5} "
              f"{slowest.seconds:>7.2f}s {'':>8}  {slowest.case.name}")


def by_station(results: list[Any]) -> None:
    """Each case that connects to the simulated station (its robot type checked against the
    controller's): the time to refuse on its first run (cold: the command's imports not yet done in
    this process, which started the station) and its second (warm)."""
    rs = [r for r in results if r.case.station]
    if not rs:
        return
    print("\nCases that connect (a robot type the simulated UR5e's controller contradicts): time to refuse")
    print(f"{'case':<60} {'meets':>5} {'cold':>8} {'warm':>8}")
    for r in rs:
        print(f"{r.case.name:<60} {'yes' if r.ok else 'no':>5} {r.seconds:>7.2f}s "
              f"{WARM.get(r.case.name, float('nan')):>7.2f}s")


# ------------------------------------------------------------------------------------------ faults

POSES, VALIDATION, CANDIDATES = 12, 4, 2000
SIGNALS = (signal.SIGKILL, signal.SIGINT, signal.SIGTERM)


@dataclass
class Fault:
    """One interruption and what the run after it did."""

    trial: int
    signum: int
    after_points: int
    phase: str
    exit_code: int | None = None
    problems: list[str] = field(default_factory=list)
    leftovers: int = 0

    @property
    def exact(self) -> bool:
        return not self.problems


def _command(db: Path, seed: int) -> list[str]:
    return [sys.executable, "-m", "hil", "calibrate", "--sim", "--speed", "50", "--seed", str(seed),
            "--poses", str(POSES), "--validation", str(VALIDATION), "--candidates", str(CANDIDATES),
            "--db", str(db), "--json"]


def _descendants(pid: int) -> set[int]:
    """Every live process below `pid` (from /proc)."""
    children: dict[int, list[int]] = defaultdict(list)
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as fh:
                    ppid = int(fh.read().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children[ppid].append(int(entry))
    out, todo = set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            if child not in out:
                out.add(child)
                todo.append(child)
    return out


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@dataclass
class Run:
    """One `hil calibrate` process: its exit code, the roles of the points it measured, whether the fault
    was injected, and (after SIGKILL) how many of its processes outlived it by 10 s."""

    code: int | None
    roles: list[str]
    fired: bool = False
    leftovers: int = 0


RUN_LIMIT = 300.0  # s: a run that takes longer is killed (and counted as not finishing)


def run_once(cmd: list[str], log: Path, kill: tuple[int, int, float] | None) -> Run:
    """Run `cmd`; with `kill` = (signal, after this many measured points, extra delay in s), interrupt it
    then."""
    with open(log, "a") as err:
        proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=err, text=True,
                                start_new_session=True)
        watchdog = threading.Timer(RUN_LIMIT, lambda: _kill_group(proc.pid))
        watchdog.start()
        run = Run(None, [])
        try:
            assert proc.stdout is not None
            for line in proc.stdout:
                try:
                    event = json.loads(line)
                except json.JSONDecodeError:
                    continue
                if event.get("event") != "PointMeasured":
                    continue
                run.roles.append(str(event.get("role", "?")))
                if kill is None or run.fired or len(run.roles) < kill[1]:
                    continue
                run.fired = True
                signum, _, delay = kill
                time.sleep(delay)
                family = _descendants(proc.pid)
                if signum == signal.SIGINT:  # Ctrl-C: the terminal's whole foreground group
                    os.killpg(proc.pid, signum)
                else:  # kill -9 / kill: the process alone
                    os.kill(proc.pid, signum)
                if signum == signal.SIGKILL:
                    proc.wait()
                    deadline = time.monotonic() + 10.0
                    while time.monotonic() < deadline and any(_alive(p) for p in family):
                        time.sleep(0.2)
                    left = [p for p in family if _alive(p)]
                    run.leftovers = len(left)
                    for p in left:
                        with contextlib.suppress(ProcessLookupError):
                            os.kill(p, signal.SIGKILL)
                    break
            proc.wait(timeout=RUN_LIMIT)
        finally:
            watchdog.cancel()
            if proc.poll() is None:
                _kill_group(proc.pid)
                proc.wait()
            _kill_group(proc.pid)  # whatever is left of its group (the simulator, ur_rtde's client)
    run.code = proc.returncode
    return run


def _kill_group(pgid: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pgid, signal.SIGKILL)


def _state(db: Path) -> dict[str, Any]:
    """The campaigns, poses and measurements in the store (read-only)."""
    if not db.exists():
        return {"campaigns": {}, "poses": {}, "measurements": {}}
    conn = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    try:
        campaigns = dict(conn.execute("SELECT id, status FROM campaigns"))
        poses = {(c, i): (role, target, status, reason) for c, i, role, target, status, reason in
                 conn.execute("SELECT campaign, idx, role, target, status, reason FROM poses")}
        measurements: dict[tuple[str, int], list[tuple[int, float]]] = defaultdict(list)
        for mid, c, pose, t in conn.execute("SELECT id, campaign, pose, t FROM measurements ORDER BY id"):
            measurements[(c, pose)].append((mid, t))
    finally:
        conn.close()
    return {"campaigns": campaigns, "poses": poses, "measurements": dict(measurements)}


def _resume_problems(before: dict[str, Any], after: dict[str, Any]) -> list[str]:
    """What the run after a fault did that an exact resume does not."""
    problems = []
    if before["campaigns"] and set(after["campaigns"]) != set(before["campaigns"]):
        problems.append(f"started a new campaign ({len(after['campaigns'])} campaigns, "
                        f"{len(before['campaigns'])} before)")
    changed = [k[1] for k, v in before["poses"].items() if k in after["poses"]
               and json.loads(after["poses"][k][1]) != json.loads(v[1])]
    if changed:
        problems.append(f"re-planned {len(changed)} pose(s) already planned (e.g. index {changed[0]})")
    dropped = [k[1] for k in before["poses"] if k not in after["poses"]]
    if dropped:
        problems.append(f"dropped {len(dropped)} planned pose(s)")
    again = [k[1] for k, rows in before["measurements"].items() if after["measurements"].get(k) != rows]
    if again:
        problems.append(f"measured {len(again)} pose(s) again that were measured before the fault")
    return problems


def _final_problems(state: dict[str, Any]) -> list[str]:
    """What a finished campaign must be: one, finished, every pose visited once, the counts asked for."""
    problems = []
    if len(state["campaigns"]) != 1:
        return [f"{len(state['campaigns'])} campaigns in the store, expected 1"]
    (cid, status), = state["campaigns"].items()
    if status not in ("accepted", "rejected"):
        problems.append(f"campaign status {status!r}, not finished")
    poses = {k: v for k, v in state["poses"].items() if k[0] == cid}
    pending = [k[1] for k, v in poses.items() if v[2] not in ("measured", "skipped")]
    if pending:
        problems.append(f"{len(pending)} planned pose(s) neither measured nor skipped")
    silent = [k[1] for k, v in poses.items() if v[2] == "skipped" and not v[3]]
    if silent:
        problems.append(f"{len(silent)} pose(s) skipped without a reason")
    twice = [k[1] for k, rows in state["measurements"].items() if k[0] == cid and len(rows) > 1]
    if twice:
        problems.append(f"{len(twice)} pose(s) measured more than once "
                        f"({sum(len(r) for r in state['measurements'].values())} points for "
                        f"{len(state['measurements'])} poses)")
    unplanned = [k[1] for k in state["measurements"] if k[0] == cid and k not in poses]
    if unplanned:
        problems.append(f"{len(unplanned)} measurement(s) of unplanned poses")
    roles = defaultdict(int)
    for role, *_ in poses.values():
        roles[role] += 1
    if roles["calibration"] != POSES or roles["validation"] != VALIDATION:
        problems.append(f"planned {roles['calibration']} calibration and {roles['validation']} validation "
                        f"poses, asked for {POSES} and {VALIDATION}")
    return problems


def faults(count: int, seed: int, kills_per_trial: int, keep: bool) -> tuple[int, int, bool]:
    """Inject `count` faults; print the table; return (faults injected, resumed exactly, baseline ok)."""
    rng = random.Random(seed)
    work = Path(tempfile.mkdtemp(prefix="hil-faults-"))
    print(f"\nFaults: hil calibrate --sim --speed 50, {POSES} calibration + {VALIDATION} validation poses, "
          f"seed {seed}", flush=True)
    try:
        db = work / "baseline.db"
        base = run_once(_command(db, 100), work / "baseline.log", None)
        base_problems = _final_problems(_state(db))
        if base.code not in (0, 1):
            base_problems.insert(0, f"exit {base.code}")
        total_points = len(base.roles) or 30
        print(f"baseline (no fault): exit {base.code}, {len(base.roles)} points; "
              + ("checks pass" if not base_problems else "FAILS: " + "; ".join(base_problems)), flush=True)

        done: list[Fault] = []
        trial = 0
        print(f"{'#':>3} {'trial':>5} {'signal':<8} {'after':>5} {'phase':<12} {'exit':>5} {'left':>4}  "
              "resumed exactly?")
        while len(done) < count and trial < count * 3:
            trial += 1
            db = work / f"trial-{trial}.db"
            log = work / f"trial-{trial}.log"
            cmd = _command(db, 100 + trial)
            states = [_state(db)]  # states[j]: the store before run j of this trial
            at: dict[int, Fault] = {}  # run index -> the fault that interrupted it
            finished = False
            for _ in range(min(kills_per_trial, count - len(done))):
                signum = rng.choice(SIGNALS)
                after = rng.randint(1, max(1, total_points - 2))  # points measured in the trial so far
                delay = rng.uniform(0.0, 0.6)
                measured = sum(len(r) for r in states[-1]["measurements"].values())
                run = run_once(cmd, log, (signum, max(1, after - measured), delay))
                states.append(_state(db))
                if not run.fired:  # the campaign finished before the moment came
                    finished = run.code in (0, 1)
                    break
                fault = Fault(trial, signum, max(after, measured + 1), run.roles[-1], run.code,
                              leftovers=run.leftovers)
                expected = {signal.SIGKILL: -9, signal.SIGINT: 130, signal.SIGTERM: 143}[signum]
                if run.code != expected:
                    fault.problems.append(f"exit {run.code} after {signal.Signals(signum).name}, "
                                          f"expected {expected}")
                at[len(states) - 2] = fault
            attempts = 0
            while not finished and attempts < 5:  # re-run the same command until the campaign finishes
                run = run_once(cmd, log, None)
                states.append(_state(db))
                finished = run.code in (0, 1)
                attempts += 1
            final = _final_problems(states[-1])
            if not finished:
                final.insert(0, f"the campaign did not finish in {attempts} re-runs (last exit {run.code})")
            for j, fault in at.items():  # judged on the run after it (interrupted or not) and the end
                fault.problems += _resume_problems(states[j + 1], states[j + 2]) + final
            for fault in at.values():
                done.append(fault)
                print(f"{len(done):>3} {fault.trial:>5} {signal.Signals(fault.signum).name:<8} "
                      f"{fault.after_points:>5} {fault.phase:<12} {fault.exit_code!s:>5} "
                      f"{fault.leftovers:>4}  "
                      + ("yes" if fault.exact else "NO: " + "; ".join(fault.problems)), flush=True)
        exact = sum(1 for f in done if f.exact)
        left = sum(f.leftovers for f in done)
        print(f"total: {len(done)} faults injected, {exact} resumed exactly, "
              f"{len(done) - exact} not; {left} process(es) outlived a kill -9 by 10 s")
        return len(done), exact, not base_problems
    finally:
        if keep:
            print(f"stores and logs kept in {work}")
        else:
            shutil.rmtree(work, ignore_errors=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--faults", type=int, default=10, help="faults to inject (default: 10)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the fault moments (default: 1)")
    ap.add_argument("--kills-per-trial", type=int, default=2,
                    help="faults injected into one campaign before it is let finish (default: 2)")
    ap.add_argument("--only", help="comma list of subcommands of the bad-input table (default: all)")
    ap.add_argument("--no-sweep", action="store_true", help="skip the bad-input table")
    ap.add_argument("--classes", action="store_true",
                    help="only the cases of the classes (ids c1-... to c6-...)")
    ap.add_argument("--station", action="store_true",
                    help="only the cases that connect to the simulated station (a robot type checked "
                         "against the controller)")
    ap.add_argument("--no-faults", action="store_true", help="skip the fault injection")
    ap.add_argument("--verbose", action="store_true", help="print why each failing case fails")
    ap.add_argument("--keep", action="store_true", help="keep the fault trials' stores and logs")
    args = ap.parse_args()
    if args.faults < 1 or args.kills_per_trial < 1:
        ap.error("--faults and --kills-per-trial must be at least 1")
    ok = True
    if not args.no_sweep:
        cases, meeting = sweep(set(args.only.split(",")) if args.only else None, args.verbose, args.classes,
                               args.station)
        ok &= cases == meeting
    if not args.no_faults:
        injected, exact, baseline = faults(args.faults, args.seed, args.kills_per_trial, args.keep)
        ok &= injected == exact and baseline
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
