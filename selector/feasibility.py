"""Requests that geometry alone proves empty, refused before a single candidate is drawn.

`selector.candidates.generate_candidates` asks `impossible` first; only what it cannot prove goes to
sampling, whose own give-up bound costs seconds.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from selector.arm import point_segment_distance
from selector.model import PoseModel


class Settings(Protocol):
    """What `impossible` reads of `selector.candidates.Constraints` (which imports this module)."""

    tracker: Sequence[float] | None
    tracker_range: tuple[float, float]
    keep_in_lower: Sequence[float]
    keep_in_upper: Sequence[float]
    floor: float

    def enabled(self) -> tuple[str, ...]: ...


#: Configurations drawn to measure the arm's fixed geometry for `impossible` (its bounds hold for any
#: number; a few dozen catch a chain whose shoulder or base is not fixed after all).
_PROBES = 64
#: Spread (m) below which a point of the probed chain counts as fixed: far below any capsule radius.
_FIXED = 1e-9


def impossible(model: PoseModel, constraints: Settings, lo: np.ndarray, hi: np.ndarray
               ) -> tuple[str, str] | None:
    """(constraint, why) when geometry alone proves that no configuration passes, else None.

    Sampling cannot prove emptiness: it gives up only after tens of thousands of draws (seconds of
    work, and tens of seconds on a loaded machine), which is how ``hil select --tracker 0,0,0`` took
    15–35 s to be refused. These bounds are sound for any configuration, so a refusal here
    is never wrong; a request they do not catch still falls back to sampling:

    * the SMR stays within R of the shoulder point (joint 2's origin, on joint 1's axis): R is the sum
      of the chain's fixed origin-to-origin lengths from joint 2 to the flange plus the SMR offset
      (triangle inequality), so a tracker farther than range max + R, or closer than range min − R,
      leaves ``range`` empty, and a keep-in box farther than R from the shoulder leaves ``keep-in``
      empty;
    * the base capsule does not move: a tracker inside it has every beam ending inside a link
      (``line-of-sight``);
    * the upper arm's capsule starts at the shoulder's height whatever the joints (joint 2's axis is
      horizontal on every UR): a floor above that start less the capsule's radius leaves ``floor``
      empty.

    The fixed points are measured on `_PROBES` configurations drawn in the sampling box `lo`..`hi`
    and used only when they did not move, so a model of another structure is never refused by them.
    """
    c = constraints
    enabled = set(c.enabled())
    dof = len(lo)
    q = np.vstack([np.clip(np.zeros(dof), lo, hi),
                   lo + (hi - lo) * np.random.default_rng(0).random((_PROBES - 1, dof))])
    F = model.frames(q)
    o = F[:, :, :3, 3]
    smr = np.einsum("nij,j->ni", F[:, -1, :3, :3], np.asarray(model.smr, float)) + o[:, -1]
    segs = model.arm.segments(F, smr)
    radii = np.asarray(model.arm.radii, float)
    shoulder = o[0, 1]
    wobble = float(np.max(np.linalg.norm(o[:, 1] - shoulder, axis=1)))
    links = np.linalg.norm(np.diff(o[:, 1:], axis=1), axis=2).sum(axis=1)
    reach = float(np.max(links)) + float(np.linalg.norm(model.smr)) + wobble
    if c.tracker is not None:
        tracker = np.asarray(c.tracker, float)
        away = float(np.linalg.norm(tracker - shoulder))
        if "range" in enabled and away - reach > c.tracker_range[1]:
            return "range", (f"the tracker is {away:.2f} m from the shoulder and the SMR reaches at most "
                             f"{reach:.2f} m from it, so every SMR is beyond the range's "
                             f"{c.tracker_range[1]:g} m")
        if "range" in enabled and away + reach < c.tracker_range[0]:
            return "range", (f"the tracker is {away:.2f} m from the shoulder and the SMR reaches at most "
                             f"{reach:.2f} m from it, so every SMR is nearer than the range's "
                             f"{c.tracker_range[0]:g} m")
        base = segs[:, 0]
        if ("line-of-sight" in enabled and np.ptp(base, axis=0).max() < _FIXED
                and point_segment_distance(tracker, base[0, 0], base[0, 1]) < radii[0]):
            return "line-of-sight", ("the tracker stands inside the robot's base (a capsule of "
                                     f"{radii[0] * 1e3:.0f} mm radius up to the shoulder), so no beam "
                                     "reaches it")
    if "keep-in" in enabled:
        nearest = np.clip(shoulder, c.keep_in_lower, c.keep_in_upper)
        gap = float(np.linalg.norm(nearest - shoulder))
        if gap > reach:
            return "keep-in", (f"the keep-in box is {gap:.2f} m from the shoulder and the SMR reaches at "
                               f"most {reach:.2f} m from it")
    if "floor" in enabled:
        root = segs[:, 2, 0, 2]  # the upper arm's start (z), capsule index 2
        top = float(root[0]) - float(radii[2])
        if np.ptp(root) < _FIXED and c.floor > top:
            return "floor", (f"the floor at {c.floor:g} m is above the upper arm's root ({top:.3f} m, "
                             "the shoulder's height less the capsule's radius) in every posture")
    return None
