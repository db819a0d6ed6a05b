"""The Results screen says how precise the validation RMS is (the stored result's
``validation.precision``), in one line under the verdict that still fits 80x24."""

from __future__ import annotations

import asyncio
import dataclasses

from hil.tui.messages import CampaignLoaded
from tests.hil.tui.conftest import screen_text, wait_for
from tests.hil.tui.test_snapshots import SIZE, offline_app, record

PRECISION = {"design": "clustered", "poses": 4, "clusters": 2, "rms_standard_error": 1.84e-6,
             "design_effect": 2.13}


def test_the_results_screen_shows_the_standard_error_under_the_verdict() -> None:
    async def scenario() -> str:
        app = offline_app()
        finished = record()
        result = {**finished.result, "validation": {"precision": PRECISION}}  # a finished campaign's
        shown = dataclasses.replace(finished, result=result)
        async with app.run_test(size=SIZE) as pilot:
            app.post_message(CampaignLoaded(shown))
            # the footer redraws its keys once the table is shown: wait for that frame, not one pause
            await wait_for(pilot, lambda: "HTML report" in screen_text(app), 10.0, "the footer's keys")
            return screen_text(app)

    text = asyncio.run(scenario())
    lines = text.splitlines()
    verdict = next(k for k, line in enumerate(lines) if "PASS" in line)
    assert lines[verdict + 1].strip() == "validation RMS ± 1.8 µm (1 s.e., 2 clusters, design effect 2.1)"
    # still one screen: every parameter row and the footer's keys
    assert "tracker.ty" in text and "HTML report" in lines[-1] and len(lines) <= SIZE[1]


def test_without_a_precision_block_there_is_no_line() -> None:
    async def scenario() -> str:
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            app.post_message(CampaignLoaded(record()))
            await pilot.pause()
            return screen_text(app)

    assert "1 s.e." not in asyncio.run(scenario())
