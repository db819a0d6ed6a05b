"""Results at 80x24: each number whole and said once (issue 29, items 2, 3 and 5 of the TUI's round 2).

A fit of 40 poses of which 10 are the bootstrap's says so ("40 used of 40" alone read as 40
calibration poses against the configuration's 30); a verification's model path was cut at its end
("out/20261127-161234-a1b8-mod…"), the part that names the file.
"""

from __future__ import annotations

import asyncio
import copy

from hil.tui.messages import CampaignLoaded
from hil.tui.words import shorten_middle
from tests.hil.tui.conftest import screen_text, wait_for
from tests.hil.tui.test_second_round import VERIFICATION, verification_record
from tests.hil.tui.test_snapshots import SIZE, offline_app, record

MODEL = "out/calibrations/station-7/20261127-161234-a1b8-model.json"


def with_bootstrap() -> object:
    rec = record()
    model = copy.deepcopy(rec.model.doc)
    model["fit"].update(poses=40, used=40)
    result = {"model": model, "poses": {"bootstrap": {"planned": 10, "measured": 10},
                                        "calibration": {"planned": 30, "measured": 30},
                                        "validation": {"planned": 20, "measured": 20}}}
    models = [type(rec.models[0])(**{**rec.models[0].__dict__, "doc": model})]
    return type(rec)(**{**rec.__dict__, "result": result, "models": models})


def test_the_fit_panel_says_the_bootstrap_poses_among_those_it_used():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            app.post_message(CampaignLoaded(with_bootstrap()))
            await wait_for(pilot, lambda: "40 used of 40" in screen_text(app), 5, "the fit drawn")
            text = screen_text(app)
            assert "= 30 + 10 bootstrap" in text, text
            assert "…" not in text, text

    asyncio.run(scenario())


def test_a_fit_without_bootstrap_says_nothing_more():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            app.post_message(CampaignLoaded(record()))
            await wait_for(pilot, lambda: "18 used of 18" in screen_text(app), 5, "the fit drawn")
            assert "bootstrap" not in screen_text(app)

    asyncio.run(scenario())


def test_a_verifications_model_shows_its_file_name_whole_and_its_path_in_full():
    rec = verification_record()
    doc = {**copy.deepcopy(VERIFICATION), "model": {"source": MODEL, "sha256": "0" * 64}}
    rec = type(rec)(**{**rec.__dict__, "result": doc})

    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            app.post_message(CampaignLoaded(rec))
            await wait_for(pilot, lambda: "VERIFIED" in screen_text(app), 5, "the verdict")
            text = screen_text(app)
            assert "20261127-161234-a1b8-model.json" in text, text  # the file name, whole, in the panel
            assert f"model {MODEL}" in text, text  # and the whole path under the verdict
            assert "…" not in text, text
            verdict = next(line for line in text.splitlines() if "VERIFIED" in line)
            assert verdict.endswith("300/300 poses"), text  # on one line, not wrapped at 80

    asyncio.run(scenario())


def test_shorten_middle_keeps_both_ends():
    assert shorten_middle("20261127-161234-a1b8-model.json", 31) == "20261127-161234-a1b8-model.json"
    short = shorten_middle("20261127-161234-a1b8-verification-model.json", 29)
    assert len(short) == 29 and short.startswith("20261127-1612") and short.endswith("model.json")
    assert "…" in short
