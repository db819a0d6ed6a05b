"""A whole MOVEB plan: positions (bridges + LP + point-error iteration), orientations, dense samples
and the timed trajectory. This is what `hil moveb plan` writes and `hil moveb run` streams."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import BSpline

from hil.files.outputs import atomic_write_text, format_csv
from hil.moveb.bridge import BridgeShape, Curve
from hil.moveb.optimise import Solution, plan_positions
from hil.moveb.orientation import axis_splines, orthonormal_frames
from hil.moveb.program import Program
from hil.moveb.timing import Limits, TimeLaw, feed_profile

SAMPLES_HEADER = ("s", "x", "y", "z", "i", "j", "k", "u", "v", "w", "curvature")


@dataclass(frozen=True)
class Samples:
    """Dense samples of the planned trajectory (mm, unit axes, 1/mm)."""

    s: np.ndarray
    position: np.ndarray
    z_axis: np.ndarray
    x_axis: np.ndarray
    curvature: np.ndarray
    dcurvature: np.ndarray

    def rows(self) -> np.ndarray:
        return np.column_stack([self.s, self.position, self.z_axis, self.x_axis, self.curvature])


@dataclass
class Plan:
    """The planned MOVEB trajectory of one program."""

    program: Program
    continuity: str
    solution: Solution
    s_keys: np.ndarray
    z_spline: BSpline
    x_spline: BSpline
    seconds: float  # planning time

    @property
    def curve(self) -> Curve:
        return self.solution.curve

    @property
    def length(self) -> float:
        return self.curve.length

    def frames(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Orthonormal tool Z and X axes at arc lengths s."""
        s = np.clip(np.asarray(s, float), 0.0, self.length)
        return orthonormal_frames(self.z_spline(s), self.x_spline(s), self.program.source)

    def at(self, s: np.ndarray) -> Samples:
        ev = self.curve.evaluate(s)
        z, x = self.frames(ev["s"])
        return Samples(ev["s"], ev["position"], z, x, ev["curvature"], ev["dcurvature"])

    def sample_grid(self, step: float = 0.5, per_bridge: int = 64) -> np.ndarray:
        """Arc lengths every `step` mm plus `per_bridge` through every bridge (short bridges too)."""
        grid = self.curve.arclength_grid(step)
        bridge_s = self.curve.bridge_arclengths(per_bridge)
        return np.unique(np.r_[grid, bridge_s])

    def dense(self, step: float = 0.5, per_bridge: int = 64) -> Samples:
        return self.at(self.sample_grid(step, per_bridge))

    def timed(self, limits: Limits, rate_hz: float,
              ceiling: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[TimeLaw, Samples]:
        """The time law under `limits` (and a speed `ceiling` along s, if given) and the trajectory
        at the controller's samples."""
        grid = self.curve.arclength_grid(min(0.05, max(self.length / 1000.0, 1e-3)))
        grid = np.unique(np.r_[grid, self.curve.bridge_arclengths(64)])
        law = feed_profile(grid, self.curve.evaluate(grid)["curvature"], limits, rate_hz, ceiling=ceiling)
        return law, self.at(law.s)


def plan_program(program: Program, continuity: str = "G2", beta: float = 0.5) -> Plan:
    """Plan positions and orientations of a validated program (see `hil.moveb` modules)."""
    t0 = time.perf_counter()
    shape = BridgeShape(continuity, beta=beta)
    solution = plan_positions(program.positions, program.d, program.e, shape)
    s_keys = solution.curve.point_arclength()
    z_spline, x_spline = axis_splines(s_keys, program.z_axes, program.x_axes, continuity)
    return Plan(program, continuity, solution, s_keys, z_spline, x_spline, time.perf_counter() - t0)


def write_samples(path: str, samples: Samples) -> None:
    """samples.csv with the header of docs/design.md, Contracts: MOVEB files (mm, unit vectors, 1/mm)."""
    atomic_write_text(path, format_csv(SAMPLES_HEADER, samples.rows()))


def summary(plan: Plan) -> dict[str, object]:
    """Figures a user checks after planning (JSON-friendly)."""
    sol = plan.solution
    groups = []
    for g in plan.program.groups():
        idx = np.arange(g.start, g.stop)
        groups.append({"lines": [int(plan.program.lines[g.start]), int(plan.program.lines[g.stop - 1])],
                       "points": len(idx), "D": float(plan.program.d[g.start]),
                       "E": float(plan.program.e[g.start]),
                       "max_point_error": float(sol.point_error[idx].max()),
                       "max_shift": float(sol.shift[idx].max())})
    return {"points": len(plan.program.points), "continuity": plan.continuity,
            "length_mm": plan.length, "bridges": len(plan.curve.bridged),
            "iterations": sol.iterations, "fallback": sol.fallback,
            "planning_ms": plan.seconds * 1e3, "groups": groups,
            "finite": bool(math.isfinite(plan.length))}
