"""The operator's lines for the warm-up and drift-watch events (`hil.campaign.warmup`).

One wording for the CLI's progress lines and the TUI's run screen. Kept apart from `hil.campaign.warmup`
so the terminal's progress printer does not load the kinematics (pinocchio) when the CLI starts.
"""

from __future__ import annotations

import math
from typing import Any

from hil.campaign.events import DriftFlagged, ReferenceMeasured, WarmupFinished, WarmupProgress

#: `ReferenceMeasured.phase`: measured while warming up, or while measuring (the drift watch).
WARMUP, DRIFT = "warmup", "drift"


def um(metres: float | None) -> str:
    """A length in micrometres for a progress line ("12.3 µm")."""
    return "?" if metres is None else f"{metres * 1e6:.1f} µm"


def _seconds(value: float | None) -> str:
    """A time constant's upper limit for a progress line ("905 s"; "?" when the fit gave none)."""
    return "?" if value is None or not math.isfinite(value) else f"{value:.0f} s"


def describe(event: Any) -> str | None:
    """The operator's line for a warm-up or drift event (CLI progress, TUI run screen); None for others."""
    if isinstance(event, WarmupProgress):
        ahead = ("still to come: judged from the 4th measurement" if event.remaining is None else
                 f"about {um(event.remaining)} still to come")
        if (event.remaining_upper is None or event.time_constant is None  # (stored before the evidence)
                or not math.isfinite(event.remaining_upper)):  # (too few measurements for an upper limit)
            return (f"warm-up: reference moved {um(event.moved)} in {event.interval:.0f} s, {ahead} "
                    f"(limit {um(event.limit)}), {event.elapsed / 60:.0f} of at most "
                    f"{event.max_time / 60:.0f} min")
        source = "joint temperatures" if event.time_constant_source == "temperatures" else "positions"
        flat = "; joints flat" if event.temperatures_flat else ""
        span = "" if event.span is None else f" over {event.span / 60:.0f} min"
        return (f"warm-up: reference moved {um(event.moved)} in {event.interval:.0f} s, {ahead} "
                f"(limit {um(event.limit)}), at most {um(event.remaining_upper)}; τ "
                f"{event.time_constant:.0f} s, at most {_seconds(event.time_constant_upper)} (from the "
                f"{source}){span}{flat}; {event.elapsed / 60:.0f} of at most {event.max_time / 60:.0f} min")
    if isinstance(event, WarmupFinished):
        if event.converged:
            if event.decision:  # the rule's own words: which rule, on what evidence
                return f"warm-up: done after {event.seconds / 60:.1f} min, {event.decision}"
            return (f"warm-up: done after {event.seconds / 60:.1f} min: about {um(event.remaining)} of drift "
                    f"still to come (limit {um(event.limit)})")
        why = event.reason or (f"about {um(event.remaining)} of drift still to come "
                               f"(limit {um(event.limit)})")
        return (f"warning: warm-up stopped after {event.seconds / 60:.1f} min without settling: {why}; "
                "measuring anyway")
    if isinstance(event, ReferenceMeasured) and event.phase == DRIFT:
        if event.baseline:
            return "drift: reference measured (the baseline later measurements are compared with)"
        return f"drift: reference {um(event.drift)} from its baseline"
    if isinstance(event, DriftFlagged):
        return (f"WARNING: drift: the reference moved {um(event.drift)} from its baseline, beyond the "
                f"{um(event.limit)} limit: the campaign is flagged (its verdict still comes from validation)")
    return None
