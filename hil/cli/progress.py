"""Event subscribers for a terminal: a progress bar with ETA (or plain lines) and JSON lines.

Both are non-critical subscribers: if the terminal goes away, the campaign carries on.
"""

from __future__ import annotations

import json
import sys
import time
from typing import IO

from hil.campaign.events import (
    Event,
    Message,
    PhaseChanged,
    PlanReady,
    PointMeasured,
    PoseSkipped,
    Resumed,
    RunFinished,
    RunStarted,
    Suspended,
)


class JsonLines:
    """One JSON object per event (``event.to_dict()``), one line each, flushed at once."""

    def __init__(self, stream: IO[str] | None = None) -> None:
        self.stream = stream or sys.stdout

    def __call__(self, event: Event) -> None:
        self.stream.write(json.dumps(event.to_dict()) + "\n")
        self.stream.flush()


class Progress:
    """Human progress on stderr: a redrawn bar with ETA on a terminal, plain lines otherwise."""

    def __init__(self, stream: IO[str] | None = None, bar: bool | None = None, width: int = 28) -> None:
        self.stream = stream or sys.stderr
        self.bar = self.stream.isatty() if bar is None else bar
        self.width = width
        self.total = 0
        self.done = 0
        self.started = time.monotonic()
        self.first_measure: float | None = None
        self.done_at_first = 0
        self._drawn = False

    def _line(self, text: str) -> None:
        if self._drawn:
            self.stream.write("\r\x1b[K")
            self._drawn = False
        self.stream.write(text + "\n")
        self.stream.flush()

    def _eta(self) -> str:
        if self.first_measure is None or self.done <= self.done_at_first:
            return "--:--"
        rate = (time.monotonic() - self.first_measure) / (self.done - self.done_at_first)
        left = max(0.0, rate * (self.total - self.done))
        return f"{int(left // 60):02d}:{int(left % 60):02d}"

    def _draw(self, note: str) -> None:
        if not self.bar:
            return
        frac = self.done / self.total if self.total else 0.0
        filled = round(frac * self.width)
        text = (f"[{'#' * filled}{'.' * (self.width - filled)}] {self.done}/{self.total} poses  "
                f"ETA {self._eta()}  {note}")
        self.stream.write("\r\x1b[K" + text[:120])
        self.stream.flush()
        self._drawn = True

    def __call__(self, event: Event) -> None:
        if isinstance(event, RunStarted):
            self.total, self.done = event.poses, event.measured
            what = "resuming" if event.resumed else "starting"
            done = f", {event.measured} measured" if event.resumed else ""
            self._line(f"{what} campaign {event.campaign} on {event.robot} ({event.station}), "
                       f"{event.poses} poses planned (calibration + validation){done}")
        elif isinstance(event, PlanReady):  # the plan's own count (a resumed plan includes the measured)
            self.total = sum(1 for p in event.poses if p["role"] != "bootstrap")
        elif isinstance(event, PhaseChanged):
            self._line(f"{event.phase}: {event.detail}" if event.detail else event.phase)
        elif isinstance(event, PointMeasured):
            if event.role != "bootstrap":
                self.done += 1
                if self.first_measure is None:
                    self.first_measure, self.done_at_first = time.monotonic(), self.done
            dev = "" if event.deviation is None else f", {event.deviation * 1e3:.3f} mm from nominal"
            note = f"pose {event.index} ({event.role}){dev}"
            if self.bar:
                self._draw(note)
            else:
                self._line(f"measured {note}")
        elif isinstance(event, PoseSkipped):
            self._line(f"skipped pose {event.index} ({event.role}): {event.reason}")
        elif isinstance(event, Suspended):
            self._line(f"SUSPENDED ({event.kind}): {event.message}")
        elif isinstance(event, Resumed):
            self._line(f"resumed after {event.kind} ({event.waited:.1f} s)")
        elif isinstance(event, Message):
            self._line(f"{event.level}: {event.text}")
        elif isinstance(event, RunFinished):
            self._line(f"campaign {event.campaign} {event.status}"
                       + (f": {event.detail}" if event.detail else ""))
