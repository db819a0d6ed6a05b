"""Day one, second round (items 11-13): what the Plan, Results, History, Station and Help screens and
the command palette say, from canned state (no station, no clock)."""

from __future__ import annotations

import asyncio

from hil.station.config import default_config
from hil.store import CampaignRecord, RobotIdentity
from hil.tui.messages import CampaignLoaded, HistoryLoaded, StationChanged
from hil.tui.state import StationState
from tests.hil.tui.conftest import screen_text, wait_for
from tests.hil.tui.test_snapshots import SIZE, T0, offline_app, record, summary

VERIFICATION = {"format": "hil-verification/1", "cycles": 30, "modes": ["uncompensated", "compensated"],
                "results": {"uncompensated": {"AP_max": 1.2345e-3, "RP_max": 2.1e-5, "AP_mean": 0.9e-3},
                            "compensated": {"AP_max": 4.56e-5, "RP_max": 1.9e-5, "AP_mean": 3.1e-5}}}


def verification_record() -> CampaignRecord:
    s = summary("20231115-080000-beef", "accepted", T0 + 3600, None)
    s = type(s)(**{**s.as_dict(), "kind": "verification", "planned": 300, "measured": 300, "passed": None})
    return CampaignRecord(summary=s, robot=RobotIdentity("ur5e", "20235500001"),
                          config=default_config().as_dict(), config_hash="0" * 64,
                          plan={"kind": "verification"}, detail="", result=VERIFICATION, software="0.1.0")


def test_the_plan_panel_follows_the_station_once_it_is_ready():
    async def scenario():
        app = offline_app()
        config, app.session.config = app.session.config, None
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("2")
            await pilot.pause()
            assert "station not ready" in screen_text(app)
            app.session.config = config  # the station started
            app.session.station.phase = "connected"
            app.post_message(StationChanged())
            await wait_for(pilot, lambda: "keep-in" in screen_text(app), 5, "the Plan panel redrawn")
            assert "station not ready" not in screen_text(app)

    asyncio.run(scenario())


def test_results_opens_on_the_latest_campaign_of_the_store(tmp_path):
    from hil.store import Store

    store = Store.open(tmp_path / "hil.db")
    campaign = store.create_campaign(default_config().as_dict(), {"type": "ur5e", "serial": "20235500001"})
    store.set_status(campaign, "interrupted")

    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            app.session.store = store  # the station started: its store is open
            app.post_message(StationChanged())
            await pilot.pause()
            assert app.screen is app.views["station"]  # shown on Results, not switched to
            await pilot.press("4")
            await wait_for(pilot, lambda: campaign in screen_text(app), 5, "the latest campaign")
            assert "no campaign yet" not in screen_text(app)

    try:
        asyncio.run(scenario())
    finally:
        store.close()


def test_results_offers_only_the_exports_it_can_make():
    async def scenario():
        app = offline_app()
        asked = []
        app.start_export = lambda rec, kinds: asked.append(kinds)
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("4")
            await pilot.pause()
            footer = screen_text(app).splitlines()[-1]
            assert "Model" not in footer and "URDF" not in footer  # nothing to export yet
            app.post_message(CampaignLoaded(record()))
            await wait_for(pilot, lambda: "URDF" in screen_text(app).splitlines()[-1], 5, "the export keys")
            await pilot.press("u")
            assert asked == [["urdf"]]

    asyncio.run(scenario())


def test_a_verification_reads_as_a_verification_in_history_and_results():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("5")
            app.post_message(HistoryLoaded([verification_record().summary, summary()], "/tmp/hil.db"))
            await pilot.pause()
            rows = [line.split() for line in screen_text(app).splitlines()]
            assert [r[4] for r in rows if r and r[0] == "20231115-080000-beef"] == ["verified"]
            app.post_message(CampaignLoaded(verification_record()))
            await wait_for(pilot, lambda: app.screen is app.views["results"], 5, "Results")
            await pilot.pause()
            text = screen_text(app)
            assert "VERIFIED" in text and "ACCEPTED" not in text, text
            assert "accepted" not in text, text  # the Test panel's status says "verified" too
            assert "ISO 9283" in text
            assert "1.2345" in text and "0.0456" in text  # AP of each mode, mm
            assert "none yet" not in text, text
            assert "…" not in text, text  # the modes' names whole at 80 columns

    asyncio.run(scenario())


def test_help_lists_the_simulator_faults_and_the_palette_says_what_each_does():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            commands = {c.title: c.help for c in app.get_system_commands(app.screen)}
            simulator = {t: h for t, h in commands.items() if t.startswith("Simulator")}
            assert len(set(simulator.values())) == len(simulator)  # each says what it does
            assert not any("inject" in h for h in simulator.values())
            assert "block_beam" not in simulator["Simulator: unblock the tracker beam"]
            await pilot.press("question_mark")
            await pilot.pause()
            text = " ".join(screen_text(app).split())
            assert "Simulator" in text and "block the tracker beam" in text and "protective stop" in text

    asyncio.run(scenario())


def test_the_tracker_link_is_shown_whole():
    url = "socket://127.133.195.223:39712"

    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            app.session.station = StationState(phase="connected", name="simulated station", simulated=True,
                                               robot_address="127.133.195.223", tracker_url=url,
                                               tracker={"firmware": "3.6.0", "interface": "emScon TPI 3.6.0"})
            app.post_message(StationChanged())
            await pilot.pause()
            assert url in screen_text(app), screen_text(app)

    asyncio.run(scenario())
