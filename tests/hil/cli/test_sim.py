"""``hil sim`` as a user runs it: one JSON line with every address, then serving until Ctrl-C."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np

from drivers.tracker import EmsconConfig, EmsconTracker, GeoComTracker, SerialConfig, TcpConfig, TrackerConfig
from mocks.ur.testing import random_loopback

ROOT = Path(__file__).resolve().parents[3]


def test_sim_prints_both_tracker_protocols_and_both_answer_for_the_same_smr() -> None:
    address = random_loopback()
    argv = [sys.executable, "-m", "hil", "sim", "--address", address, "--control-port", "0", "--seed", "3"]
    proc = subprocess.Popen(argv, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        assert proc.stdout is not None
        info = json.loads(proc.stdout.readline())
        assert info["robot"]["address"] == address
        tracker = info["tracker"]
        assert tracker["emscon_url"].startswith(f"tcp://{address}:") and tracker["url"].startswith("socket://")
        with EmsconTracker(EmsconConfig(TcpConfig(tracker["emscon_url"]), measure_time_ms=100)) as em:
            a = em.measure_point(1).xyz
        with GeoComTracker(TrackerConfig(SerialConfig(tracker["url"]))) as gc:
            b = gc.measure_point(3).xyz
        assert np.linalg.norm(a - b) < 200e-6  # one world, one SMR, two protocols
    finally:
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=20)
