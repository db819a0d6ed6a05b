"""A sweep's progress and stream health in one line each, for every front-end alike.

The CLI's progress lines and the terminal app's Run screen say the same words for the same events:
the tour planned (segments, those a resumed campaign already has), each segment recorded (its
number of the tour's, samples per stream, beam breaks), and the join (the clock map and its σ, the
samples used and those left out by reason). Short enough for an 80-column terminal.
"""

from __future__ import annotations

from hil.campaign.events import (
    BOOTSTRAP_SEGMENTS,
    Event,
    SweepFitted,
    SweepPlanned,
    SweepSegmentDone,
    is_bootstrap_segment,
)


def describe(event: Event) -> str | None:
    """The line for a sweep event, or None for any other event."""
    if isinstance(event, SweepPlanned):
        seconds = sum(float(s.get("seconds", 0.0)) for s in event.segments)
        had = f", {len(event.done)} recorded before" if event.done else ""
        return (f"sweep: {len(event.segments)} segments through {len(event.waypoints)} poses, "
                f"{seconds:.1f} s of motion{had}")
    if isinstance(event, SweepSegmentDone):
        health = f", {event.breaks} beam break{'s' if event.breaks != 1 else ''} ({event.lost} lost)" \
            if event.breaks or event.lost else ""
        boot = is_bootstrap_segment(event.segment)
        number = event.segment - BOOTSTRAP_SEGMENTS if boot else event.segment
        return (f"{'bootstrap' if boot else 'sweep'} segment {number + 1}/{event.segments}: "
                f"{event.joints} joint, {event.tracker} tracker samples{health}")
    if isinstance(event, SweepFitted):
        left = ", ".join(f"{k} {v}" for k, v in sorted(event.left_out.items()) if v) or "none"
        sigma = event.sigma_at_ref_s or event.sigma_offset_s
        return (f"sweep clock: offset {event.offset_s:.6f} s ± {sigma * 1e6:.1f} µs, "
                f"drift {event.drift * 1e6:.2f} ± {event.sigma_drift * 1e6:.2f} ppm; {event.used} samples "
                f"used, {event.rms * 1e6:.0f} µm RMS; left out: {left}")
    return None
