"""Results of a verification (ISO 9283 pose test): what it has — AP and RP of each pose — and never
the calibration's parameter table, empty (issue 29, item b)."""

from __future__ import annotations

import asyncio
import copy

from hil.tui.messages import CampaignLoaded
from tests.hil.tui.conftest import screen_text, wait_for
from tests.hil.tui.test_second_round import VERIFICATION, verification_record
from tests.hil.tui.test_snapshots import SIZE, offline_app, record


def _pose(name: str, ap: float, rp: float) -> dict:
    return {"pose": name, "n": 30, "AP_P": ap, "RP_l": rp}


def with_poses() -> object:
    rec = verification_record()
    doc = copy.deepcopy(VERIFICATION)
    results = doc["results"]
    results["uncompensated"]["poses"] = [_pose(f"P{i}", 1.1e-3 + 1e-5 * i, 2.0e-5) for i in range(1, 6)]
    # P5 of the compensated mode was measured once only: no AP/RP there
    results["compensated"]["poses"] = [*(_pose(f"P{i}", 4.0e-5 + 1e-6 * i, 1.5e-5) for i in range(1, 5)),
                                       {"pose": "P5", "n": 1, "note": "fewer than 2 attained positions"}]
    return type(rec)(**{**rec.__dict__, "result": doc})


def lines_of(text: str) -> list[list[str]]:
    return [line.split() for line in text.splitlines()]


def test_a_verification_shows_each_poses_ap_and_rp_not_an_empty_parameter_table():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            app.post_message(CampaignLoaded(with_poses()))
            await wait_for(pilot, lambda: app.screen is app.views["results"], 5, "Results")
            await wait_for(pilot, lambda: "P5" in screen_text(app), 5, "the poses drawn")
            text = screen_text(app)
            assert "parameter" not in text, text
            header = next(r for r in lines_of(text) if r[:1] == ["pose"])
            assert header == ["pose", "AP", "uncomp.", "RP", "uncomp.", "AP", "comp.", "RP", "comp."], text
            rows = {r[0]: r[1:] for r in lines_of(text) if r and r[0] in ("P1", "P5")}
            assert rows["P1"] == ["1.1100", "0.0200", "0.0410", "0.0150"], text
            assert rows["P5"] == ["1.1500", "0.0200", "-", "-"], text  # measured once: no figures
            assert "…" not in text, text

            # a calibration opened next has its parameters again
            app.post_message(CampaignLoaded(record()))
            await wait_for(pilot, lambda: "parameter" in screen_text(app), 5, "the parameter table")
            assert "P1" not in screen_text(app)

    asyncio.run(scenario())


def test_a_verification_without_per_pose_figures_shows_no_table_header():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            app.post_message(CampaignLoaded(verification_record()))
            await wait_for(pilot, lambda: app.screen is app.views["results"], 5, "Results")
            await wait_for(pilot, lambda: "VERIFIED" in screen_text(app), 5, "the verdict")
            text = screen_text(app)
            assert "parameter" not in text and "unit" not in text, text
            assert not app.screen.query_one("#params").display

    asyncio.run(scenario())


def test_history_counts_one_campaign_in_the_singular():
    from hil.tui.messages import HistoryLoaded
    from tests.hil.tui.test_snapshots import summary

    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("5")
            app.post_message(HistoryLoaded([summary()], "hil.db"))
            await wait_for(pilot, lambda: "in hil.db" in screen_text(app), 5, "the store's line")
            assert "1 campaign in hil.db" in screen_text(app)

    asyncio.run(scenario())
