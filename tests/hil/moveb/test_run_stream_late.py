"""`hil moveb run` says when its own servo stream ran late across a corner (issue 29).

On a loaded machine hil's servo loop can be starved: a real controller then stops on the last target
and goes on straight, cutting the corner, and the tracker measures that cut. The run must not be a
silent `done`: status `stream late`, exit 1, the `servo` block and a warning line. Here the send
times the driver reports are given a 0.3 s stall just before the corner (the stall hook), on the
simulated station.
"""

from __future__ import annotations

import json

import numpy as np

import hil.moveb.run
from hil.cli import main

PROGRAM = ("MOVEB 0 0 0 0 0 1 1 0 0 0.5 0.2\nMOVEB 60 0 0 0 0 1 1 0 0 0.5 0.2\n"
           "MOVEB 60 60 0 0 0 1 1 0 0 0.5 0.2\n")


def test_a_stream_starved_at_the_corner_is_stream_late(tmp_path, capsys, monkeypatch) -> None:
    real = hil.moveb.run.stream_timing

    def stalled(times, rate_hz, lookahead_s, path_mm=None):  # type: ignore[no-untyped-def]
        t = np.array(times, dtype=float)
        P = np.asarray(path_mm, dtype=float)
        ab = P[-1] - P[0]
        off = np.linalg.norm(np.cross(P - P[0], ab), axis=1) / np.linalg.norm(ab)
        k = int(np.argmax(off)) - 20  # 20 samples before the corner, the loop is starved for 0.3 s
        t[k:] += 0.3
        t[k:k + 40] = t[k] + np.arange(40) * 1e-5  # then sends what is due in a burst
        t[k + 40:] = t[k + 39] + (np.arange(len(t) - k - 40) + 1) / rate_hz
        return real(t, rate_hz, lookahead_s, path_mm)

    monkeypatch.setattr(hil.moveb.run, "stream_timing", stalled)
    out = tmp_path / "run.json"
    program = tmp_path / "short.moveb"
    program.write_text(PROGRAM)
    code = main(["moveb", "run", str(program), "--sim", "--ideal", "--speed", "5", "--out", str(out)])
    captured = capsys.readouterr()
    doc = json.loads(out.read_text())
    assert code == 1, captured.err
    assert doc["status"] == "stream late" and doc["exit_code"] == 1
    servo = doc["servo"]
    assert servo["deadline_misses"] >= 1 and servo["max_gap_s"] >= 0.3 and servo["disturbed"] is True
    assert servo["chord_mm"] > 0.01
    assert "servo stream late" in captured.err and "Traceback" not in captured.err
    assert "stream late" in captured.out and "servo stream" in captured.out
    assert doc["path_accuracy"]["max_deviation_mm"] >= 0  # the figures are still reported
