"""The Run screen's warm-up and drift line, folded from the run's events (`RunState`)."""

from __future__ import annotations

from hil.campaign.events import DriftFlagged, ReferenceMeasured, RunStarted, WarmupProgress
from hil.tui.state import RunState


def test_the_latest_line_shows_and_a_flag_stays_in_view():
    run = RunState()
    run.apply(RunStarted(campaign="c", robot="ur5e", station="s", poses=20))
    assert run.reference_line == "" and not run.drift_flagged
    run.apply(WarmupProgress(campaign="c", elapsed=130.0, moved=12e-6, interval=120.0, limit=10e-6,
                             max_time=3600.0))
    assert run.reference_line.startswith("warm-up: reference moved 12.0 µm in 120 s")
    run.apply(DriftFlagged(campaign="c", drift=41e-6, limit=30e-6, elapsed=4000.0, seq=31))
    assert run.drift_flagged and run.reference_line.startswith("WARNING: drift")
    run.apply(ReferenceMeasured(campaign="c", seq=32, run=1, phase="drift", elapsed=4100.0, q=[0.0] * 6,
                                xyz=[2.0, 0.0, 0.0], drift=5e-6))
    assert run.reference_line.startswith("WARNING: drift")  # the flag is not replaced by later lines
    run.apply(RunStarted(campaign="d", robot="ur5e", station="s", poses=20))  # a new run starts clean
    assert run.reference_line == "" and not run.drift_flagged


def test_the_run_screen_shows_the_line_at_80x24():
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
            assert "warm-up:" not in screen_text(app)  # nothing said yet: no empty line either
            app.post_message(EngineEvent(WarmupProgress(campaign="c1", t=T0 + 130, elapsed=130.0, moved=12e-6,
                                                        interval=120.0, limit=10e-6, max_time=3600.0)))
            await pilot.pause()
            text = screen_text(app)
            assert "warm-up: reference moved 12.0 µm in 120 s" in text
            app.post_message(EngineEvent(DriftFlagged(campaign="c1", t=T0 + 900, drift=41e-6, limit=30e-6,
                                                      elapsed=900.0, seq=9)))
            await pilot.pause()
            assert "WARNING: drift: the reference moved 41.0 µm" in screen_text(app)

    asyncio.run(scenario())
