"""Whether hil's servo stream kept its deadlines: what a late stream does to the path the arm takes.

A MOVEB run sends one servoJ target per controller period (docs/design.md, Facts: streaming on UR).
A real controller follows the targets as they arrive: when hil's own process is starved (a loaded
machine) a target comes late, the controller has nothing new for that long and the arm runs on
towards the last target and then jumps on to the next one — it cuts corners and hesitates on a
straight, and the tracker measures that faithfully. That is a genuine path error of the run, not of
the arm, so it is detected from the send times (`FollowResult.times`, time.monotonic) and reported
beside the figures, never hidden in them:

* a *deadline miss* is a send more than `MISS_PERIODS` periods after the previous one (the
  driver's loop keeps its period with waitPeriod; one period of jitter is the scheduler's);
* a gap longer than the servo lookahead (0.05 s for a MOVEB run) is more than the controller's own
  smoothing covers: the arm reaches the last target and stops there, then goes on to the next target
  it gets, roughly straight. Stopping on the path is no path error (ISO 9283's path accuracy is
  geometric), the straight leg is: its largest distance from the commanded path between the two
  targets (`chord_mm`) is what the lateness can have added. Beyond `CHORD_TOLERANCE_MM` the run is
  `stream late` (exit 1): its figures describe a disturbed motion, not how well the arm follows a path.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

#: A send later than this many periods after the previous one missed its deadline (see above).
MISS_PERIODS = 2.0
#: mm: a chord cut by a late stream below this is not seen in the figures: a fifth of one reading's
#: standard deviation at 3 m (docs/design.md, Facts: tracker accuracy: 7.5 µm + 3 µrad · 3 m ≈ 12 µm
#: per axis); an assumption of where "not seen" begins, not a published figure.
CHORD_TOLERANCE_MM = 0.002


@dataclass(frozen=True)
class StreamTiming:
    """How the servo stream kept its period."""

    period_s: float  # the controller period the stream was due at
    samples: int
    misses: int  # sends more than MISS_PERIODS periods after the previous one
    max_gap_s: float  # the longest time between two sends
    late_s: float  # the stream's total time beyond its schedule ((N-1) periods)
    lookahead_s: float
    chord_mm: float = 0.0  # the largest cut a gap beyond the lookahead can have made (module docstring)

    @property
    def stopped(self) -> bool:
        """Whether a gap exceeded the lookahead: the arm stopped and went on straight."""
        return self.max_gap_s > self.lookahead_s

    @property
    def disturbed(self) -> bool:
        """Whether that straight leg cut the path by more than `CHORD_TOLERANCE_MM`."""
        return self.stopped and self.chord_mm > CHORD_TOLERANCE_MM

    def as_dict(self) -> dict[str, Any]:
        return {"period_s": self.period_s, "samples": self.samples, "deadline_misses": self.misses,
                "max_gap_s": self.max_gap_s, "late_s": self.late_s, "lookahead_s": self.lookahead_s,
                "chord_mm": self.chord_mm, "disturbed": self.disturbed}

    def warning(self) -> str | None:
        """One line for the operator when a deadline was missed, else None."""
        if not self.misses:
            return None
        verdict = (f"more than the lookahead: the arm stopped and cut the path by up to "
                   f"{self.chord_mm:.3f} mm, which the path figures include" if self.disturbed else
                   f"more than the lookahead, but the arm's straight leg stays within {self.chord_mm:.3f} mm "
                   "of the path" if self.stopped else "within the lookahead")
        return (f"servo stream late: {self.misses} of {self.samples} targets missed their "
                f"{self.period_s * 1e3:.0f} ms deadline, longest gap {self.max_gap_s * 1e3:.0f} ms "
                f"({verdict}); a loaded machine starves hil's servo loop: run on an idle one")


def chord_cut(path: np.ndarray, i: int, j: int) -> float:
    """The largest distance (path units) of `path[i..j]` from the straight segment path[i]-path[j]."""
    a, b = path[i], path[j]
    pts = path[i:j + 1]
    ab = b - a
    L2 = float(ab @ ab)
    u = np.clip((pts - a) @ ab / L2, 0.0, 1.0) if L2 > 0 else np.zeros(len(pts))
    return float(np.max(np.linalg.norm(pts - (a + u[:, None] * ab), axis=1)))


def stream_timing(times: np.ndarray, rate_hz: float, lookahead_s: float,
                  path_mm: np.ndarray | None = None) -> StreamTiming:
    """The timing of a stream whose targets were sent at `times` (s, monotonic) at `rate_hz`.

    `path_mm` (N, 3): the commanded tool position of each target, for the cut of every gap longer
    than the lookahead (module docstring); the targets sent late sit between the two around the gap.
    """
    t = np.asarray(times, dtype=float)
    period = 1.0 / float(rate_hz)
    gaps = np.diff(t) if t.size > 1 else np.zeros(0)
    chord = 0.0
    if path_mm is not None and gaps.size:
        P = np.asarray(path_mm, dtype=float)
        # the controller holds the target before the gap, then gets the one after it: whatever was
        # sent in a burst after a stall arrives within a period, so the leg runs to the burst's last
        for k in np.flatnonzero(gaps > lookahead_s):
            j = k + 1
            while j + 1 < len(t) and t[j + 1] - t[j] < 0.5 * period:
                j += 1
            chord = max(chord, chord_cut(P, int(k), int(j)))
    return StreamTiming(period, int(t.size), int(np.count_nonzero(gaps > MISS_PERIODS * period)),
                        float(gaps.max()) if gaps.size else 0.0,
                        float(max(t[-1] - t[0] - (t.size - 1) * period, 0.0)) if t.size else 0.0,
                        float(lookahead_s), chord)
