"""The farthest a station's parts may be from each other: the bounds `hil.station.config` checks a
configuration against and the commands check their options against (``hil identify --smr``, ``hil select
--tracker``). A module of its own, importing nothing, so a command that checks one option does not load
the whole configuration reader (`hil identify`'s start-up: bench/cli_startup.py).
"""

from __future__ import annotations

__all__ = ["MAX_KEEP_IN", "MAX_SMR_OFFSET", "MAX_TRACKER_DISTANCE"]

#: The farthest a tracker may stand from the robot base (m): the selector keeps the SMR within the
#: tracker's measuring range, 0.8-20 m (`selector.candidates.Constraints.tracker_range`, Leica AT960's
#: stated range), and the SMR stays within the arm's reach (at most 1.75 m, UR20) of the base.
MAX_TRACKER_DISTANCE = 20.0 + 1.75

#: The farthest the SMR may sit from the flange (m): a nest or a short tool holds it a few centimetres
#: out; half a metre is already a tool as long as a UR5e's upper arm, and 10 m is a value in millimetres.
MAX_SMR_OFFSET = 0.5

#: Keep-in box corners (m, robot base frame): the largest arm (UR20) reaches 1.75 m, so a corner beyond
#: 5 m keeps nothing in and is a value typed in millimetres.
MAX_KEEP_IN = 5.0
