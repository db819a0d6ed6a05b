"""Event subscribers for a terminal: a progress bar with ETA (or plain lines) and JSON lines.

Both are non-critical subscribers: if the terminal goes away, the campaign carries on.

A calibration and an ISO 9283 verification (``hil verify``, ``hil calibrate --verify``) run on the same
engine and emit the same events; `Progress` words them by what the events say. The plan's `PlanReady`
tells a verification (its selection's ``"kind": "verification"``; each visit's pose P1–P5, mode and
cycle), but `RunStarted` comes first: its line waits for the next event, so it can say which it is.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Mapping
from typing import IO, Any

from hil.campaign.events import (
    AcquisitionStopped,
    ControllerModel,
    DriftFlagged,
    Event,
    Message,
    PhaseChanged,
    PlanReady,
    PointMeasured,
    PoseSkipped,
    ReferenceMeasured,
    Resumed,
    RunFinished,
    RunStarted,
    StateChanged,
    Suspended,
    SweepFitted,
    SweepPlanned,
    SweepSegmentDone,
    WarmupFinished,
    WarmupProgress,
)
from hil.campaign.reference_lines import describe as describe_reference
from hil.campaign.sweep_lines import describe as describe_sweep

#: `PlanReady.selection["kind"]` of a verification (`hil.verify.verification_plan.KIND`; not imported, so
#: that the CLI's start-up does not load the verification's kinematics).
VERIFICATION = "verification"
#: Events that may come between `RunStarted` and the plan's `PlanReady` and print nothing.
_SILENT = (ControllerModel, StateChanged)


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
        self._started: RunStarted | None = None  # its line, until the next event says what runs
        self.selection: Mapping[str, Any] = {}  # the plan's (PlanReady): a verification says so
        self.visits: dict[int, Mapping[str, Any]] = {}  # a verification's visits by index

    @property
    def verification(self) -> bool:
        """Whether the run is an ISO 9283 verification (its plan said so), not a calibration."""
        return self.selection.get("kind") == VERIFICATION

    @property
    def _unit(self) -> str:
        return "visits" if self.verification else "poses"

    def _visit(self, index: int) -> str:
        """What a verification's visit is: its pose, mode and cycle ("P3 compensated, cycle 2 of 30")."""
        v = self.visits.get(index) or {}
        if not {"pose", "mode", "cycle"} <= set(v):
            return ""
        return f"{v['pose']} {v['mode']}, cycle {v['cycle']} of {self.selection.get('cycles', '?')}"

    def _what(self, index: int, role: str) -> str:
        """A point's name in a line: a calibration's pose and role, a verification's visit."""
        if not self.verification:
            return f"pose {index} ({role})"
        visit = self._visit(index)
        return f"visit {index} ({visit})" if visit else f"visit {index}"

    def _deviation(self, deviation: float | None) -> str:
        """A calibration's points are compared with the nominal arm's prediction, a verification's with
        the pose's commanded position (`hil.verify.result.deviation`; known with a model only)."""
        if deviation is None:
            return ""
        return f", {deviation * 1e3:.3f} mm from {'commanded' if self.verification else 'nominal'}"

    def _say_started(self) -> None:
        event, self._started = self._started, None
        if event is None:
            return
        what = "resuming" if event.resumed else "starting"
        done = f", {event.measured} measured" if event.resumed else ""
        if self.verification:
            modes = " and ".join(self.selection.get("modes") or []) or "?"
            self._line(f"{what} verification {event.campaign} on {event.robot} ({event.station}), "
                       f"{event.poses} visits planned (poses P1–P5, {self.selection.get('cycles', '?')} "
                       f"cycles, {modes}){done}")
        else:
            self._line(f"{what} campaign {event.campaign} on {event.robot} ({event.station}), "
                       f"{event.poses} poses planned (calibration + validation){done}")

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
        text = (f"[{'#' * filled}{'.' * (self.width - filled)}] {self.done}/{self.total} {self._unit}  "
                f"ETA {self._eta()}  {note}")
        self.stream.write("\r\x1b[K" + text[:120])
        self.stream.flush()
        self._drawn = True

    def __call__(self, event: Event) -> None:
        if isinstance(event, RunStarted):
            self._say_started()  # an earlier run's line still waiting, if any
            self.total, self.done = event.poses, event.measured
            self._started = event
            return
        if isinstance(event, PlanReady):  # the plan's own count (a resumed plan includes the measured)
            self.total = sum(1 for p in event.poses if p["role"] != "bootstrap")
            self.selection = dict(event.selection or {})
            self.visits = {int(p["index"]): p for p in event.poses} if self.verification else {}
        if isinstance(event, _SILENT):
            return
        self._say_started()
        if isinstance(event, PhaseChanged):
            self._line(f"{event.phase}: {event.detail}" if event.detail else event.phase)
        elif isinstance(event, PointMeasured):
            if event.role != "bootstrap":
                self.done += 1
                if self.first_measure is None:
                    self.first_measure, self.done_at_first = time.monotonic(), self.done
            dev = self._deviation(event.deviation)
            if self.bar:  # the count is on the bar: a verification's note is the visit's pose alone
                visit = self._visit(event.index) if self.verification else ""
                self._draw((visit or self._what(event.index, event.role)) + dev)
            else:
                self._line(f"measured {self._what(event.index, event.role)}{dev}")
        elif isinstance(event, PoseSkipped):
            self._line(f"skipped {self._what(event.index, event.role)}: {event.reason}")
        elif isinstance(event, AcquisitionStopped):  # the stopping rule: fewer poses to go
            self.total = max(self.done, self.total - event.poses_left)
            self._line(f"stopping early: {event.reason}; {event.poses_left} calibration poses not needed")
        elif isinstance(event, Suspended):
            self._line(f"SUSPENDED ({event.kind}): {event.message}")
        elif isinstance(event, Resumed):
            self._line(f"resumed after {event.kind} ({event.waited:.1f} s)")
        elif isinstance(event, Message):
            self._line(f"{event.level}: {event.text}")
        elif isinstance(event, WarmupProgress | WarmupFinished | ReferenceMeasured | DriftFlagged):
            line = describe_reference(event)  # warm-up and drift watch (hil.campaign.warmup)
            if line is not None:
                self._line(line)
        elif isinstance(event, SweepPlanned | SweepSegmentDone | SweepFitted):
            line = describe_sweep(event)  # the sweep's progress and its streams' health
            if line is not None:
                self._line(line)
        elif isinstance(event, RunFinished):
            # a finished verification is stored "accepted" (it has no threshold): say "finished"
            status = "finished" if self.verification and event.status == "accepted" else event.status
            self._line(f"{'verification' if self.verification else 'campaign'} {event.campaign} {status}"
                       + (f": {event.detail}" if event.detail else ""))
