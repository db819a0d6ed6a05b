"""`stream_during`: the tracker's samples for the length of a motion, its failure after the motion."""

from __future__ import annotations

import threading

import pytest

from drivers.tracker.device import StreamSample
from drivers.tracker.during import stream_during
from drivers.tracker.errors import ConnectionLost


class FakeTracker:
    """Streams a sample every millisecond until stopped, or fails after `fail_after` samples."""

    def __init__(self, fail_after: int | None = None) -> None:
        self.fail_after = fail_after

    def stream(self, rate_hz, *, stop: threading.Event):
        k = 0
        while not stop.wait(0.001):
            if self.fail_after is not None and k >= self.fail_after:
                raise ConnectionLost("link dropped")
            yield StreamSample(float(k), (0.0, 0.0, float(k)), None, stamp=float(k))
            k += 1


def test_the_samples_of_the_motion_and_what_it_returned():
    moved = threading.Event()
    samples, result = stream_during(FakeTracker(), 1000.0, lambda: moved.wait(0.05) or "done")
    assert result == "done" and len(samples) > 5
    assert [s.stamp for s in samples] == [float(k) for k in range(len(samples))]


def test_a_stream_failure_is_raised_after_the_motion_ran_whole():
    finished = []
    with pytest.raises(ConnectionLost, match="link dropped"):
        stream_during(FakeTracker(fail_after=3), 1000.0,
                      lambda: threading.Event().wait(0.05) or finished.append(1))
    assert finished == [1]


def test_a_motion_failure_is_raised_as_it_is():
    def motion():
        raise RuntimeError("protective stop")

    with pytest.raises(RuntimeError, match="protective stop"):
        stream_during(FakeTracker(fail_after=0), 1000.0, motion)
