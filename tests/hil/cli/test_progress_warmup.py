"""``hil calibrate``'s progress lines for the warm-up and the drift watch (plain lines, as in a log)."""

from __future__ import annotations

import io

from hil.campaign.events import (
    DriftFlagged,
    ReferenceMeasured,
    RunFinished,
    WarmupFinished,
    WarmupProgress,
)
from hil.cli.support.progress import Progress

Q = [0.0] * 6


def lines(*events) -> list[str]:
    out = io.StringIO()
    progress = Progress(out, bar=False)
    for event in events:
        progress(event)
    return out.getvalue().splitlines()


def test_the_warm_up_and_drift_lines():
    got = lines(
        ReferenceMeasured(campaign="c", seq=1, run=1, phase="warmup", elapsed=10.0, q=Q, xyz=[2, 0, 0]),
        WarmupProgress(campaign="c", elapsed=130.0, moved=12.34e-6, interval=120.0, limit=10e-6,
                       max_time=3600.0),
        WarmupProgress(campaign="c", elapsed=780.0, moved=6.1e-6, interval=121.0, limit=10e-6,
                       max_time=3600.0, remaining=23.4e-6, time_constant=880.0),
        WarmupFinished(campaign="c", seconds=2900.0, converged=True, references=25, moved=3e-6, limit=10e-6,
                       remaining=4.2e-6, time_constant=900.0),
        ReferenceMeasured(campaign="c", seq=26, run=1, phase="drift", elapsed=3100.0, q=Q, xyz=[2, 0, 0],
                          drift=8.2e-6, limit=30e-6),
        DriftFlagged(campaign="c", drift=41e-6, limit=30e-6, elapsed=4000.0, seq=31),
        RunFinished(campaign="c", status="accepted",
                    detail="validation RMS 0.0300 mm <= 0.1000 mm; drift flagged: the reference moved "
                           "41.0 µm (limit 30.0 µm)"))
    assert got == [
        "warm-up: reference moved 12.3 µm in 120 s, still to come: judged from the 4th measurement "
        "(limit 10.0 µm), 2 of at most 60 min",
        "warm-up: reference moved 6.1 µm in 121 s, about 23.4 µm still to come (limit 10.0 µm), 13 of at "
        "most 60 min",
        "warm-up: done after 48.3 min: about 4.2 µm of drift still to come (limit 10.0 µm)",
        "drift: reference 8.2 µm from its baseline",
        "WARNING: drift: the reference moved 41.0 µm from its baseline, beyond the 30.0 µm limit: the "
        "campaign is flagged (its verdict still comes from validation)",
        "campaign c accepted: validation RMS 0.0300 mm <= 0.1000 mm; drift flagged: the reference moved "
        "41.0 µm (limit 30.0 µm)",
    ]


def test_a_warm_up_that_did_not_settle_is_a_warning_line():
    (line,) = lines(WarmupFinished(campaign="c", seconds=3600.0, converged=False, references=30,
                                   moved=9e-6, limit=10e-6, remaining=18e-6, time_constant=2000.0))
    assert line == ("warning: warm-up stopped after 60.0 min without settling: about 18.0 µm of drift "
                    "still to come (limit 10.0 µm); measuring anyway")


def test_a_check_with_its_evidence_says_the_upper_limits_and_where_tau_came_from():
    (line, done) = lines(
        WarmupProgress(campaign="c", elapsed=1560.0, moved=2.2e-6, interval=131.0, limit=10e-6,
                       max_time=3600.0, remaining=10.1e-6, time_constant=826.0, remaining_upper=16.9e-6,
                       time_constant_upper=922.0, time_constant_source="temperatures", span=1602.0,
                       temperatures_flat=False, warm=False, rule="",
                       decision="not yet: about 10.1 µm of drift still to come, and the series cannot rule "
                                "out 16.9 µm (limit 10.0 µm)"),
        WarmupFinished(campaign="c", seconds=2900.0, converged=True, references=25, moved=3e-6, limit=10e-6,
                       remaining=3.2e-6, time_constant=905.0, remaining_upper=4.4e-6,
                       time_constant_upper=922.0, span=2800.0, rule="fit",
                       decision="warm: at most 4.4 µm of drift still to come (limit 10.0 µm) over 47 min, at "
                                "least three of the longest time constants the fit allows (46 min)"))
    assert line == ("warm-up: reference moved 2.2 µm in 131 s, about 10.1 µm still to come (limit 10.0 µm), "
                    "at most 16.9 µm; τ 826 s, at most 922 s (from the joint temperatures) over 27 min; "
                    "26 of at most 60 min")
    assert done == ("warm-up: done after 48.3 min, warm: at most 4.4 µm of drift still to come "
                    "(limit 10.0 µm) over 47 min, at least three of the longest time constants the fit "
                    "allows (46 min)")
