"""Issue 19 (smaller): the simulator process lives exactly as long as the process that started it.

It used PR_SET_PDEATHSIG, which fires when the *thread* that started it ends (so a simulator started by
a worker thread died with that thread), and a service hanging in ``stop()`` kept it alive, orphaned,
after SIGTERM. Now it watches its parent process and bounds its shutdown.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from mocks.ur.controller import SimConfig
from mocks.ur.process import _PARENT_POLL, _STOP_GRACE
from mocks.ur.testing import start_sim
from tests.proc_tree import alive, wait_gone

ROOT = Path(__file__).resolve().parents[3]

# Starts the simulator from a worker thread that then ends, prints the simulator's pid, lives on.
OWNER = """
import threading, time
from mocks.ur.testing import start_sim

if __name__ == "__main__":
    box = []
    worker = threading.Thread(target=lambda: box.append(start_sim(speed=10.0)))
    worker.start()
    worker.join()
    print(box[0]._proc.pid, flush=True)
    time.sleep(60)
"""


class _Hangs:
    """A service whose stop() never returns."""

    def start(self) -> dict:
        return {}

    def stop(self) -> None:
        threading.Event().wait()


def hanging_service(controller: object) -> _Hangs:
    return _Hangs()


def test_outlives_the_thread_that_started_it_but_not_the_process(tmp_path):
    script = tmp_path / "owner.py"
    script.write_text(OWNER)
    owner = subprocess.Popen([sys.executable, str(script)], cwd=ROOT, stdout=subprocess.PIPE,
                             text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    try:
        assert owner.stdout is not None
        sim_pid = int(owner.stdout.readline())
        time.sleep(1.0)  # the starting thread has ended well before
        assert alive(sim_pid), "the simulator died with the thread that started it"
        os.kill(owner.pid, signal.SIGKILL)
        owner.wait(5)
        # its promise: noticed within a poll, ended within the grace; the rest is a loaded machine's
        assert wait_gone([sim_pid], _PARENT_POLL + _STOP_GRACE + 2.0) == set(), \
            "the simulator outlived its parent"
    finally:
        if owner.poll() is None:
            owner.kill()
            owner.wait(5)


def test_sigterm_ends_it_even_when_a_service_hangs_in_stop():
    sim = start_sim(SimConfig(speed=10.0), services=[f"{__name__}:hanging_service"])
    proc = sim._proc
    assert proc is not None
    try:
        proc.terminate()
        proc.wait(_STOP_GRACE + 2.0)  # TimeoutExpired: SIGTERM left it running
    finally:
        sim.stop()
