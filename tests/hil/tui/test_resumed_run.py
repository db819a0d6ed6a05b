"""A resumed campaign on the Run screen: what the campaign already has is shown, and counted as the
console and the store count it (issue 29, item a: after a resume the table was empty and the header
had lost its "(+10 bootstrap)")."""

from __future__ import annotations

import asyncio

from hil.tui.screens.dialogs import ResumeDialog
from tests.hil.tui.conftest import press_to_close, screen_text, wait_for
from tests.hil.tui.fake_station import FakeStation

SIZE = (80, 24)


def test_a_resumed_run_shows_the_points_measured_before_with_the_stores_counts(tmp_path, monkeypatch):
    st = FakeStation(tmp_path, monkeypatch, hold_move=15)
    st.config = st.config.with_overrides(tracker__position=None)  # located by the bootstrap's points

    async def interrupted() -> str:
        app = st.app()
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("3", "g")
            await wait_for(pilot, lambda: st.arm.holding.is_set(), 60, "the arm in the middle of a move")
            await pilot.press("q")
            await press_to_close(pilot, "y", 15)
        return app.run_state.campaign

    campaign = asyncio.run(interrupted())
    stored = st.store.campaign(campaign).summary
    assert stored.status == "interrupted" and stored.bootstrap_measured == 10 and stored.measured >= 2
    points = st.store.measured_poses(campaign)

    st.arm.holding.clear()
    st.arm.hold_move = st.arm.moves + 2  # the resumed run measures one pose, then holds

    async def resumed() -> None:
        app = st.app()
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("3", "g")
            await wait_for(pilot, lambda: isinstance(app.screen, ResumeDialog), 10, "the resume question")
            await pilot.press("r")
            await wait_for(pilot, lambda: st.arm.holding.is_set(), 60, "the resumed run moving")
            run = app.run_state
            assert run.campaign == campaign and run.resumed_with == stored.measured
            assert run.measured == stored.measured + 1
            # every point the store holds is in the table, as measured, with its stored deviation
            earlier = {(r.role, r.index): r for r in run.rows.values() if r.status == "measured"}
            assert {(m.role, i) for i, m in points.items()} <= set(earlier)
            for i, m in points.items():
                assert earlier[(m.role, i)].deviation == m.deviation
                assert earlier[(m.role, i)].p == list(m.p)
            table = app.screen.query_one("#poses")
            await wait_for(pilot, lambda: table.row_count >= len(points), 10, "the earlier points drawn")
            # the header counts as the store and `hil calibrate` do: the poses, the bootstrap apart
            header = f"{stored.measured + 1}/{stored.planned} poses (+10 bootstrap)"
            await wait_for(pilot, lambda: header in screen_text(app), 10, "the header")
            # the resumed run's own point is registered on all the campaign has, as it would have
            # been uninterrupted: it has a deviation (it had none: registered on its own points)
            new = [r for r in run.rows.values() if r.status == "measured" and (r.role, r.index) not in
                   {(m.role, i) for i, m in points.items()}]
            assert len(new) == 1 and new[0].deviation is not None
            await pilot.press("q")
            await press_to_close(pilot, "y", 15)

    asyncio.run(resumed())
    st.store.close()
