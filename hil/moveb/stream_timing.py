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
  smoothing covers: the arm has reached the last target and stops. Such a run is `stream late`
  (exit 1): its figures describe the disturbed motion, not how well the arm follows a path.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

#: A send later than this many periods after the previous one missed its deadline (see above).
MISS_PERIODS = 2.0


@dataclass(frozen=True)
class StreamTiming:
    """How the servo stream kept its period."""

    period_s: float  # the controller period the stream was due at
    samples: int
    misses: int  # sends more than MISS_PERIODS periods after the previous one
    max_gap_s: float  # the longest time between two sends
    late_s: float  # the stream's total time beyond its schedule ((N-1) periods)
    lookahead_s: float

    @property
    def disturbed(self) -> bool:
        """Whether a gap exceeded the lookahead: the arm stopped and jumped on (module docstring)."""
        return self.max_gap_s > self.lookahead_s

    def as_dict(self) -> dict[str, Any]:
        return {"period_s": self.period_s, "samples": self.samples, "deadline_misses": self.misses,
                "max_gap_s": self.max_gap_s, "late_s": self.late_s, "lookahead_s": self.lookahead_s,
                "disturbed": self.disturbed}

    def warning(self) -> str | None:
        """One line for the operator when a deadline was missed, else None."""
        if not self.misses:
            return None
        verdict = ("more than the lookahead: the arm stopped and jumped on, so the path figures include "
                   "hil's lateness" if self.disturbed else "within the lookahead")
        return (f"servo stream late: {self.misses} of {self.samples} targets missed their "
                f"{self.period_s * 1e3:.0f} ms deadline, longest gap {self.max_gap_s * 1e3:.0f} ms "
                f"({verdict}); a loaded machine starves hil's servo loop: run on an idle one")


def stream_timing(times: np.ndarray, rate_hz: float, lookahead_s: float) -> StreamTiming:
    """The timing of a stream whose targets were sent at `times` (s, monotonic) at `rate_hz`."""
    t = np.asarray(times, dtype=float)
    period = 1.0 / float(rate_hz)
    gaps = np.diff(t) if t.size > 1 else np.zeros(0)
    return StreamTiming(period, int(t.size), int(np.count_nonzero(gaps > MISS_PERIODS * period)),
                        float(gaps.max()) if gaps.size else 0.0,
                        float(max(t[-1] - t[0] - (t.size - 1) * period, 0.0)) if t.size else 0.0,
                        float(lookahead_s))
