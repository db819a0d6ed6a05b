"""The Results verdict line says whose threshold it applied: the automatic rule's or the user's."""

from __future__ import annotations

import asyncio
import dataclasses

import pytest

from hil.tui.messages import CampaignLoaded
from tests.hil.tui.conftest import screen_text, wait_for
from tests.hil.tui.test_snapshots import SIZE, offline_app, record


@pytest.mark.parametrize(("rule", "word"), [("auto", " auto"), ("threshold", " set")])
def test_the_verdict_line_names_the_rule(rule: str, word: str) -> None:
    async def scenario() -> str:
        app = offline_app()
        finished = record()
        result = {**finished.result, "verdict": {"passed": True, "rule": rule, "reason": "-"}}
        async with app.run_test(size=SIZE) as pilot:
            app.post_message(CampaignLoaded(dataclasses.replace(finished, result=result)))
            await wait_for(pilot, lambda: "PASS" in screen_text(app), 10.0, "the verdict")
            return screen_text(app)

    line = next(line for line in asyncio.run(scenario()).splitlines() if "PASS" in line)
    assert line.rstrip().endswith(f"mm{word}") and len(line) <= SIZE[0]
