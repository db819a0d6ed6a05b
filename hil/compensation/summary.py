"""What a compensation did to a file: how far each target moved, and what it could not touch.

The figures a user checks before running a compensated program: shifts of a few millimetres and turns
of a few milliradians are the controller's factory calibration meeting hil's; tens of millimetres mean
the wrong model or the wrong robot. Targets the rewrite could not compensate (computed at run time)
are listed with their line, never dropped silently.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hil.compensation.solve import Compensated


@dataclass(frozen=True)
class Moved:
    """One compensated target: where it is (a line, a name) and how far it moved."""

    line: int
    what: str  # "movel", "Waypoint_1_p", "row"
    shift: float  # m
    turn: float  # rad

    def as_dict(self) -> dict[str, Any]:
        return {"line": self.line, "what": self.what, "shift_mm": self.shift * 1e3,
                "turn_mrad": self.turn * 1e3}


@dataclass(frozen=True)
class Skipped:
    """A target left as it is, and why."""

    line: int
    what: str
    reason: str

    def as_dict(self) -> dict[str, Any]:
        return {"line": self.line, "what": self.what, "reason": self.reason}


@dataclass
class Summary:
    """The report of one compensated file."""

    source: str
    kind: str  # "csv" or "urscript"
    joints: bool = False  # --joints: move arguments (CSV rows) written as joint targets
    moved: list[Moved] = field(default_factory=list)
    not_compensated: list[Skipped] = field(default_factory=list)  # moves whose target is computed at run time
    left_alone: list[Skipped] = field(default_factory=list)  # pose variables no move goes to
    as_joints: int = 0  # literals written as joint lists

    def add(self, line: int, what: str, c: Compensated) -> None:
        self.moved.append(Moved(line, what, c.shift, c.turn))

    def as_dict(self) -> dict[str, Any]:
        shifts = np.array([m.shift for m in self.moved]) * 1e3
        turns = np.array([m.turn for m in self.moved]) * 1e3

        def stats(v: np.ndarray) -> dict[str, float | None]:
            return {"mean": float(v.mean()) if v.size else None, "max": float(v.max()) if v.size else None}

        return {"input": self.source, "kind": self.kind, "joints": self.joints,
                "compensated": len(self.moved), "written_as_joints": self.as_joints,
                "shift_mm": stats(shifts), "turn_mrad": stats(turns),
                "targets": [m.as_dict() for m in self.moved],
                "not_compensated_count": len(self.not_compensated),
                "not_compensated": [s.as_dict() for s in self.not_compensated],
                "pose_variables_left_alone": [s.as_dict() for s in self.left_alone]}

    def text(self) -> str:
        """The summary for a person (stderr)."""
        doc = self.as_dict()
        n = doc["compensated"]
        lines = [f"{self.source}: {n} target{'s' if n != 1 else ''} compensated"]
        if n:
            s, t = doc["shift_mm"], doc["turn_mrad"]
            lines[0] += (f": shift mean {s['mean']:.3f} mm, max {s['max']:.3f} mm; "
                         f"turn mean {t['mean']:.3f} mrad, max {t['max']:.3f} mrad")
        if self.joints and self.kind == "urscript":
            lines.append(f"  {self.as_joints} move argument(s) written as joint targets; pose variables "
                         "stay poses (compensated)")
        if self.not_compensated:
            lines.append(f"  {len(self.not_compensated)} move(s) NOT compensated (target known only at run "
                         "time):")
            lines += [f"    line {s.line}: {s.what}: {s.reason}" for s in self.not_compensated]
        if self.left_alone:
            lines.append(f"  {len(self.left_alone)} pose variable(s) left as they are "
                         "(no move goes to them):")
            lines += [f"    line {s.line}: {s.what}: {s.reason}" for s in self.left_alone]
        return "\n".join(lines) + "\n"
