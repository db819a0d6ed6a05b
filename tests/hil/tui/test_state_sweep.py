"""The Run screen's sweep line: the segment recorded and its streams' health, then the clock the join
found, folded from the run's events (`RunState`) and shown at 80×24."""

from __future__ import annotations

from hil.campaign.events import RunStarted, SweepFitted, SweepPlanned, SweepSegmentDone
from hil.tui.state import RunState


def segment_done(k: int, lost: int = 0, breaks: int = 0, t: float = 0.0) -> SweepSegmentDone:
    return SweepSegmentDone(campaign="c1", t=t, segment=k, segments=14, take="ab", session="s", joints=1200,
                            tracker=3600, lost=lost, breaks=breaks, seconds=3.5)


FITTED = SweepFitted(campaign="c1", offset_s=-1234.567891, drift=20.1e-6, sigma_offset_s=2e-3,
                     sigma_drift=0.3e-6, used=3000, left_out={"beam lost": 120, "acceleration": 4},
                     rms=31e-6, t_ref=1300.0, sigma_at_ref_s=4.2e-6)


def test_the_sweep_line_follows_segments_then_the_clock():
    run = RunState()
    run.apply(RunStarted(campaign="c1", robot="ur5e", station="s", poses=20))
    assert run.sweep_line == ""
    run.apply(SweepPlanned(campaign="c1", segments=[{"index": 0, "seconds": 3.0},
                                                    {"index": 1, "seconds": 2.5}],
                           waypoints=[[0.0] * 6] * 3, rate_hz=500.0, tracker_rate_hz=1000.0, done=[0]))
    assert run.sweep_line == "sweep: 2 segments through 3 poses, 5.5 s of motion, 1 recorded before"
    run.apply(segment_done(2, lost=150, breaks=1))
    assert run.sweep_line == ("sweep segment 3/14: 1200 joint, 3600 tracker samples, 1 beam break "
                              "(150 lost)")
    run.apply(FITTED)
    assert run.sweep_line.startswith("sweep clock: offset -1234.567891 s ± 4.2 µs, drift 20.10 ± 0.30 ppm")
    assert "left out: acceleration 4, beam lost 120" in run.sweep_line
    run.apply(RunStarted(campaign="d", robot="ur5e", station="s", poses=20))  # a new run starts clean
    assert run.sweep_line == ""


def test_the_run_screen_shows_the_sweep_at_80x24():
    import asyncio

    from hil.tui.messages import EngineEvent
    from tests.hil.tui.conftest import screen_text
    from tests.hil.tui.test_snapshots import SIZE, T0, offline_app

    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            started = RunStarted(campaign="c1", t=T0, robot="ur5e", station="s", poses=16)
            app.post_message(EngineEvent(started))
            await pilot.pause()
            await pilot.press("3")
            await pilot.pause()
            assert "sweep" not in screen_text(app)  # nothing said yet: no empty line either
            app.post_message(EngineEvent(segment_done(4, lost=300, breaks=2, t=T0 + 60)))
            await pilot.pause()
            assert "sweep segment 5/14: 1200 joint, 3600 tracker samples, 2 beam breaks (300 lost)" \
                in screen_text(app)
            app.post_message(EngineEvent(FITTED))
            await pilot.pause()
            text = screen_text(app)
            assert "sweep clock: offset -1234.567891 s ± 4.2 µs" in text

    asyncio.run(scenario())
