"""The terminal app against the simulated station, driven by Textual's Pilot, in fast time.

One simulated station per test (starting one takes a second or two); small campaigns (12
calibration + 4 validation poses, 3000 candidates, 40x time) keep each run to a few seconds.
"""

from __future__ import annotations

import asyncio
import json
import threading

from hil.store import Store
from hil.tui.app import create_app
from hil.tui.screens.dialogs import Confirm
from hil.tui.screens.results import ResultsScreen
from tests.hil.tui.conftest import press_to_close, screen_text, wait_for

SIZE = (80, 24)
# the warm-up (an hour of the simulated arm's time) is not what these test: off
SMALL = {"campaign.calibration_poses": 12, "campaign.validation_poses": 4, "campaign.candidates": 3000,
         "warmup.enabled": False}


def sim_app(tmp_path, **kwargs):
    return create_app(sim=True, speed=40.0, seed=5, db=str(tmp_path / "hil.db"),
                      out_dir=str(tmp_path / "out"), overrides=dict(SMALL), **kwargs)


def inject_later(app, fault: str, **args) -> None:
    """Inject a fault from another thread, as the world would (the UI thread never waits for it)."""
    threading.Thread(target=app.session.sim.inject, args=(fault,), kwargs=args, daemon=True).start()


def test_connect_measure_plan_run_with_a_protective_stop_then_results_export_history(tmp_path):
    async def scenario():
        app = sim_app(tmp_path)
        async with app.run_test(size=SIZE) as pilot:
            st = app.session.station
            await wait_for(pilot, lambda: st.phase == "connected" and st.lock == "locked in", 30,
                           "the station to connect")
            # the state first, the screen a frame later (later still on a loaded machine)
            await wait_for(pilot, lambda: all(w in screen_text(app) for w in ("UR5e", "AT960", "normal")), 10,
                           "the station drawn")

            # measure now
            await pilot.press("m")
            await wait_for(pilot, lambda: st.last_point.startswith("x "), 20, "a measured point")
            await wait_for(pilot, lambda: "spread" in screen_text(app), 10, "the point drawn")

            # plan: the selector in a worker; the UI keeps answering meanwhile
            await pilot.press("2", "s")
            plan = app.views["plan"]
            await wait_for(pilot, lambda: plan.result is not None or plan.error, 60, "the selection")
            assert not plan.error, plan.error
            await wait_for(pilot, lambda: "of bound" in screen_text(app), 5, "the selection drawn")
            assert plan.result["report"]["count"] == 12

            # run: a protective stop mid-campaign shows the banner with the instruction, then clears
            await pilot.press("3", "g")
            run = app.run_state
            await wait_for(pilot, lambda: any(r.role == "calibration" and r.status == "moving"
                                              for r in run.rows.values()), 60, "the first calibration pose")
            inject_later(app, "protective_stop")
            await wait_for(pilot, lambda: run.suspended is not None, 30, "the suspension")
            assert run.suspended.kind == "protective_stop"
            banner = app.screen.query_one("#banner")
            await wait_for(pilot, lambda: banner.display and "teach pendant" in screen_text(app), 10,
                           "the banner drawn")
            inject_later(app, "clear")
            await wait_for(pilot, lambda: run.suspended is None and run.last_resumed is not None, 30,
                           "the run to resume")
            await pilot.pause()
            assert not banner.display

            # results
            await wait_for(pilot, lambda: run.finished is not None, 120, "the end of the campaign")
            results = app.views["results"]
            assert isinstance(results, ResultsScreen)
            await wait_for(pilot, lambda: app.screen is results and results.record is not None, 30,
                           "the Results screen")
            await wait_for(pilot, lambda: "PASS" in screen_text(app), 5, "the verdict drawn")
            text = screen_text(app)
            assert run.finished.status == "accepted", run.finished.detail
            assert "PASS" in text and "joint2" in text and "before" in text

            # exports
            await pilot.press("x")
            await wait_for(pilot, lambda: len(results.written) == 4 or results.export_error, 60,
                           "the exports")
            assert not results.export_error
            out = tmp_path / "out"
            model = json.loads((out / f"{run.campaign}-model.json").read_text())
            assert model["format"] == "hil-model/1"
            assert "<robot" in (out / f"{run.campaign}.urdf").read_text()
            assert "PASS" in (out / f"{run.campaign}-report.html").read_text()

            # history lists it; enter opens it in Results
            await pilot.press("5")
            history = app.views["history"]
            await wait_for(pilot, lambda: history.rows, 20, "the history")
            assert history.rows[0].id == run.campaign and history.rows[0].status == "accepted"
            await pilot.press("enter")
            await wait_for(pilot, lambda: app.screen is results, 20, "Results from History")
            await press_to_close(pilot, "q")
        assert app.return_value == 0
        with Store.open(tmp_path / "hil.db") as store:
            assert store.campaign(run.campaign).summary.status == "accepted"

    asyncio.run(scenario())


def test_pause_then_quit_mid_run_asks_and_leaves_the_campaign_resumable(tmp_path):
    async def scenario():
        app = sim_app(tmp_path)
        async with app.run_test(size=SIZE) as pilot:
            await wait_for(pilot, lambda: app.session.station.phase == "connected", 30, "the station")
            await pilot.press("3", "g")
            run = app.run_state
            await wait_for(pilot, lambda: run.measured >= 3, 90, "a few points")
            await pilot.press("p")  # pause: the questions below take their time, the run waits
            await wait_for(pilot, lambda: run.state == "paused", 30, "the pause")
            await wait_for(pilot, lambda: "PAUSED" in screen_text(app), 10, "the pause drawn")
            await pilot.press("q")
            await wait_for(pilot, lambda: isinstance(app.screen, Confirm), 5, "the question")
            await wait_for(pilot, lambda: "Quit?" in screen_text(app), 10, "the question drawn")
            await pilot.press("n")  # changed my mind: the run goes on
            await wait_for(pilot, lambda: not isinstance(app.screen, Confirm), 5, "the answer")
            assert app.session.run_active
            await pilot.press("q")
            await wait_for(pilot, lambda: isinstance(app.screen, Confirm), 5, "the question")
            await press_to_close(pilot, "y", 30)
        campaign = run.campaign
        # the screen's state is 'interrupted'; the run's final event may still be in flight to an app
        # that has already closed, so the store (below) is what proves the campaign resumable
        assert run.state == "interrupted", run
        assert run.finished is None or run.finished.status == "interrupted", run.finished
        with Store.open(tmp_path / "hil.db") as store:
            record = store.campaign(campaign)
            assert record.summary.status == "interrupted"
            assert record.summary.measured >= 3
            assert store.find_resumable(config_sha256=record.config_hash,
                                        robot_serial=record.robot.serial) == campaign

    asyncio.run(scenario())


def test_the_same_job_through_an_emscon_tracker_with_a_blocked_beam(tmp_path):
    """Leica's emScon TPI instead of GeoCOM: the operator's screens and the run behave the same."""
    async def scenario():
        app = create_app(sim=True, speed=40.0, seed=5, db=str(tmp_path / "hil.db"), tracker_protocol="emscon",
                         out_dir=str(tmp_path / "out"), overrides={**SMALL, "timeouts.relock": 5.0})
        async with app.run_test(size=SIZE) as pilot:
            st = app.session.station
            await wait_for(pilot, lambda: st.phase == "connected" and st.lock == "locked in", 30,
                           "the station to connect")
            assert app.session.config.tracker["protocol"] == "emscon"
            await wait_for(pilot, lambda: "AT960" in screen_text(app), 10, "the tracker drawn")
            await pilot.press("m")
            await wait_for(pilot, lambda: st.last_point.startswith("x "), 20, "a measured point")
            await pilot.press("3", "g")
            run = app.run_state
            # a wall budget, not a figure: emScon's readings are paced by the host in fast time (about
            # 2 s of wall a pose at speed 40, load 3.5; twice that on a loaded CI machine)
            await wait_for(pilot, lambda: run.measured >= 10, 180, "ten points")
            inject_later(app, "block_beam", on=True, reason="a forklift")
            await wait_for(pilot, lambda: run.suspended is not None, 30, "the suspension")
            assert run.suspended.kind == "beam_lost"
            await wait_for(pilot, lambda: "line of sight" in screen_text(app), 10, "the suspension drawn")
            inject_later(app, "block_beam", on=False)
            await wait_for(pilot, lambda: run.finished is not None, 120, "the end of the campaign")
            assert run.finished.status == "accepted", run.finished.detail
            await press_to_close(pilot, "q")
        with Store.open(tmp_path / "hil.db") as store:
            assert store.campaign(run.campaign).summary.status == "accepted"

    asyncio.run(scenario())
