"""Issue 19 (smaller): ``kill -9`` of `hil calibrate --sim` leaves no process behind.

The ur_rtde client (a multiprocessing child), multiprocessing's resource tracker and the simulated
station (its own process group) must all end within a few seconds of their parent's death; the
client was once seen alive for minutes.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

from tests.proc_tree import command_line, descendants, wait_gone

ROOT = Path(__file__).resolve().parents[3]


def test_kill_9_mid_run_leaves_no_child_process(tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "hil", "calibrate", "--sim", "--ideal", "--speed", "20",
                             "--db", str(tmp_path / "k.db"), "--out", str(tmp_path / "r.json"),
                             "--no-warmup"],
                            cwd=ROOT, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONPATH": str(ROOT)})
    try:
        assert proc.stderr is not None
        seen = []
        while not any("measured pose" in line for line in seen[-1:]):
            line = proc.stderr.readline()
            assert line, f"hil calibrate ended before measuring: {''.join(seen[-5:])}"
            seen.append(line)
        children = descendants(proc.pid)
        commands = [command_line(pid) for pid in children]
        assert any("spawn_main" in c for c in commands), commands  # the ur_rtde client
        assert any("mocks.ur" in c for c in commands), commands  # the simulated station
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(5)
        left = wait_gone(children, 5.0)  # the simulator's bound: a 0.2 s poll and a 2 s grace
        assert left == set(), [command_line(pid) for pid in left]
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5)
