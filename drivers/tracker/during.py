"""The tracker's continuous stream taken for the length of a motion.

A MOVEB run and a sweep segment both stream the tracker from a thread while the robot follows a path
in the calling thread, and keep every sample. The stream's failure (a dropped link) is raised only
once the motion has ended, so the arm is never left mid-path by the tracker's error; a failure of the
motion itself is raised as it is."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import TypeVar

from drivers.tracker.device import StreamSample, Tracker

T = TypeVar("T")


def stream_during(tracker: Tracker, rate_hz: float, motion: Callable[[], T], *, lead_s: float = 0.0,
                  join_s: float = 10.0, name: str = "tracker-stream") -> tuple[list[StreamSample], T]:
    """Run `motion()` while a thread takes `tracker.stream(rate_hz)`: (the samples, what it returned).

    `lead_s`: seconds the stream runs before the motion starts; `join_s`: the most the stream's thread
    is waited for after it (the stream ends on its stop event within one packet's wait)."""
    samples: list[StreamSample] = []
    failure: list[BaseException] = []
    stop = threading.Event()

    def take() -> None:
        try:
            for sample in tracker.stream(rate_hz, stop=stop):
                samples.append(sample)
        except BaseException as exc:  # raised after the motion
            failure.append(exc)

    thread = threading.Thread(target=take, name=name, daemon=True)
    thread.start()
    try:
        if lead_s > 0:
            time.sleep(lead_s)
        result = motion()
    finally:  # the stream ends with the motion, failed or not
        stop.set()
        thread.join(timeout=join_s)
    if failure:
        raise failure[0]
    return samples, result
