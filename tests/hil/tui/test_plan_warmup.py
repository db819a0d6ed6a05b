"""The Plan screen's warm-up toggle (w) and ``hil tui --no-warmup``: the next run's configuration has
the warm-up off, as ``hil calibrate --no-warmup``'s, and the campaign's identity is unchanged."""

from __future__ import annotations

import asyncio

from hil.station.config import default_config
from hil.tui.app import create_app
from tests.hil.tui.conftest import screen_text, wait_for

SIZE = (80, 24)


def offline_app(**options):
    app = create_app(start_station=False, sim=True, out_dir="/tmp/exports", **options)
    app.session.config = default_config()
    app.session.identity = {"robot": {"type": "ur5e"}, "campaign": {"seed": 1}}  # what finds a campaign
    return app


def test_w_on_the_plan_screen_skips_the_warmup_of_the_next_run_and_turns_it_back_on():
    async def scenario():
        app = offline_app()
        session = app.session
        identity = session.run_identity()
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("2")
            await wait_for(pilot, lambda: "warm-up on" in screen_text(app), 10, "the warm-up shown on")
            assert session.run_config().warmup["enabled"] is True
            await pilot.press("w")
            assert session.no_warmup is True
            assert session.run_config().warmup["enabled"] is False
            assert session.run_identity() == identity  # not part of what finds the campaign again
            await wait_for(pilot, lambda: "warm-up off" in screen_text(app), 10, "the warm-up shown off")
            await pilot.press("w")
            assert session.run_config().warmup["enabled"] is True
            await wait_for(pilot, lambda: "warm-up on" in screen_text(app), 10, "the warm-up shown on again")
            await pilot.press("question_mark")
            await wait_for(pilot, lambda: "w warm-up on/off" in screen_text(app), 10, "the key on ?")

    asyncio.run(scenario())


def test_the_no_warmup_option_starts_with_the_warmup_off():
    async def scenario():
        app = offline_app(no_warmup=True)
        async with app.run_test(size=SIZE) as pilot:
            assert app.session.run_config().warmup["enabled"] is False
            await pilot.press("2")
            await wait_for(pilot, lambda: "warm-up off" in screen_text(app), 10, "the warm-up shown off")

    asyncio.run(scenario())
