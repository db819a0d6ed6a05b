"""The operator's lines for the warm-up and drift-watch events (`hil.campaign.warmup`).

One wording for the CLI's progress lines and the TUI's run screen. Kept apart from `hil.campaign.warmup`
so the terminal's progress printer does not load the kinematics (pinocchio) when the CLI starts.
"""

from __future__ import annotations

from typing import Any

from hil.campaign.events import DriftFlagged, ReferenceMeasured, WarmupFinished, WarmupProgress

#: `ReferenceMeasured.phase`: measured while warming up, or while measuring (the drift watch).
WARMUP, DRIFT = "warmup", "drift"


def um(metres: float | None) -> str:
    """A length in micrometres for a progress line ("12.3 µm")."""
    return "?" if metres is None else f"{metres * 1e6:.1f} µm"


def describe(event: Any) -> str | None:
    """The operator's line for a warm-up or drift event (CLI progress, TUI run screen); None for others."""
    if isinstance(event, WarmupProgress):
        return (f"warm-up: reference moved {um(event.moved)} in {event.interval:.0f} s "
                f"(limit {um(event.limit)}), {event.elapsed:.0f} s of at most {event.max_time:.0f} s")
    if isinstance(event, WarmupFinished):
        if event.converged:
            return (f"warm-up: done after {event.seconds:.0f} s: the reference moved {um(event.moved)} "
                    f"in the last interval (limit {um(event.limit)})")
        why = event.reason or (f"the reference still moved {um(event.moved)} in the last interval "
                               f"(limit {um(event.limit)})")
        return (f"warning: warm-up stopped after {event.seconds:.0f} s without settling: {why}; "
                "measuring anyway")
    if isinstance(event, ReferenceMeasured) and event.phase == DRIFT:
        if event.baseline:
            return "drift: reference measured (the baseline later measurements are compared with)"
        return f"drift: reference {um(event.drift)} from its baseline"
    if isinstance(event, DriftFlagged):
        return (f"WARNING: drift: the reference moved {um(event.drift)} from its baseline, beyond the "
                f"{um(event.limit)} limit: the campaign is flagged (its verdict still comes from validation)")
    return None
