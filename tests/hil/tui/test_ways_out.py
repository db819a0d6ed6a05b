"""The app's ways out, its fault screens and its words, on fake devices (real engine, plan and store).

Each test runs a small campaign in-process (`tests.hil.tui.fake_station`): a second or two, no simulator.
"""

from __future__ import annotations

import asyncio
import threading
import time

import pytest

from drivers.robot.errors import EmergencyStop
from hil.campaign.events import PointMeasured, Resumed, Suspended
from hil.errors import EXIT_INTERRUPTED
from hil.tui.screens.dialogs import Confirm, ResumeDialog, Stopping
from hil.tui.session import STOP_WAIT
from hil.tui.state import StationState
from hil.tui.words import progress_words
from tests.hil.tui.conftest import press_to_close, screen_text, wait_for
from tests.hil.tui.fake_station import FakeStation

SIZE = (80, 24)
TECHNICAL = ("EmergencyStop", "TargetLost", "MOT_", "InputError", "Error:", "Exception")


def no_class_names(text: str) -> None:
    assert not [word for word in TECHNICAL if word in text], text


@pytest.mark.parametrize("key", ["ctrl+q", "ctrl+c", "q"])
def test_every_way_out_mid_run_asks_once_stops_the_arm_now_and_leaves_the_campaign_resumable(
        tmp_path, monkeypatch, key):
    st = FakeStation(tmp_path, monkeypatch, hold_move=6)

    async def scenario():
        app = st.app()
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("3", "g")
            await wait_for(pilot, lambda: st.arm.holding.is_set(), 30, "the arm in the middle of a move")
            await pilot.press(key)
            await wait_for(pilot, lambda: isinstance(app.screen, Confirm), 5, "the question")
            assert "Quit?" in screen_text(app)
            await pilot.press("ctrl+q", "ctrl+c", "q")  # one question, however many times asked
            assert sum(isinstance(s, Confirm) for s in app.screen_stack) == 1
            assert app.session.run_active and not st.arm.stopped.is_set()
            shown = []
            original = app._stop_screen

            def stop_screen(stage):  # what the operator sees meanwhile
                original(stage)
                shown.append((stage, isinstance(app.screen, Stopping)))

            app._stop_screen = stop_screen
            t0 = time.monotonic()
            await press_to_close(pilot, "y", 10)
            assert time.monotonic() - t0 < 5
            assert shown and all(on_screen for _, on_screen in shown), shown
            assert "stopping the arm" in shown[0][0]
            # once the stop is sent, the screen says so, and how long the closing may take
            stopped = [stage for stage, _ in shown if "the arm is stopped" in stage]
            assert stopped and "the app closes in a few seconds (at most" in stopped[0], shown
        assert st.arm.stopped_while_holding  # the move in progress was stopped, not finished
        assert app.return_value == EXIT_INTERRUPTED  # resumable: as `hil calibrate` interrupted
        campaign = app.run_state.campaign
        assert app.run_state.finished.status == "interrupted"
        record = st.store.campaign(campaign)
        assert record.summary.status == "interrupted" and record.summary.measured == 5
        assert st.store.find_resumable(st.config.as_dict(), robot_serial=st.arm.info.serial) == campaign

    asyncio.run(scenario())
    st.store.close()


def test_a_quit_while_the_run_is_busy_computing_still_closes_within_seconds(tmp_path, monkeypatch):
    """The plan's own computation (pose selection, identification) cannot be interrupted: the app
    stops waiting for it, marks the campaign interrupted itself and closes."""
    st = FakeStation(tmp_path, monkeypatch)
    release = threading.Event()
    busy = threading.Event()

    def slow_chooser(config):
        def choose(request):
            busy.set()
            release.wait(60.0)  # a long selection
            raise RuntimeError("released")
        return choose

    monkeypatch.setattr("hil.campaign.chooser.campaign_chooser", slow_chooser)

    async def scenario():
        app = st.app(seed=1)
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("3", "g")
            await wait_for(pilot, busy.is_set, 30, "the selection under way")
            await pilot.press("q")
            await wait_for(pilot, lambda: isinstance(app.screen, Confirm), 5, "the question")
            t0 = time.monotonic()
            await press_to_close(pilot, "y", 10)
            # nothing moves during a computation: no waiting for it to end (STOP_WAIT is for a run
            # that is measuring), only the closing of the station
            assert time.monotonic() - t0 < STOP_WAIT / 2
        # nor once the app has closed: its unmounting does not wait again for the run it gave up
        # (the process held the restored terminal for STOP_WAIT more seconds)
        assert time.monotonic() - t0 < STOP_WAIT / 2
        assert app.return_value == EXIT_INTERRUPTED
        return app.session.run_campaign

    try:
        campaign = asyncio.run(scenario())
        assert st.store.campaign(campaign).summary.status == "interrupted"
    finally:
        release.set()
    time.sleep(0.2)  # the released run thread writes nothing more
    assert st.store.campaign(campaign).summary.status == "interrupted"
    st.store.close()


def test_an_emergency_stop_says_what_to_do_and_leaves_the_campaign_resumable(tmp_path, monkeypatch):
    st = FakeStation(tmp_path, monkeypatch, estop_move=5)
    # after the run the app reconnects: the controller still reports the e-stop
    st.reconnects.append(EmergencyStop("an emergency stop is active (ROBOT_EMERGENCY_STOP)"))

    async def scenario():
        app = st.app()
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("3", "g")
            run = app.run_state
            await wait_for(pilot, lambda: run.ended, 30, "the end of the run")
            await pilot.pause()
            assert run.finished.status == "interrupted"
            text = screen_text(app)
            assert "EMERGENCY STOP" in text and "release the emergency stop" in text
            assert "power the arm on" in text and "release the brakes" in text
            assert "reconnect" in text and "g on the Run screen" in text
            no_class_names(text)
            await pilot.press("1")
            await wait_for(pilot, lambda: "power the arm on" in screen_text(app), 5, "the Station screen")
            text = screen_text(app)
            assert "EMERGENCY STOP" in text.split("Robot")[1] and "DISCONNECTED" in text
            assert "Unfinished campaign" in text
            no_class_names(text)
            # recovered: the next connect reads a normal arm and the steps go away
            await pilot.press("c")
            await wait_for(pilot, lambda: app.session.station.phase == "connected", 10, "the reconnect")
            await pilot.pause()
            assert "power the arm on" not in screen_text(app)
            assert app.session.station.safety == "normal"
            await press_to_close(pilot, "q")
        record = st.store.campaign(app.run_state.campaign)
        assert record.summary.status == "interrupted"
        assert "EmergencyStop" in str(st.store.event_log(record.id)[-1][1])  # the stored event keeps it

    asyncio.run(scenario())
    st.store.close()


def test_a_lost_beam_counts_down_to_the_skip_and_the_operator_skips_now(tmp_path, monkeypatch):
    st = FakeStation(tmp_path, monkeypatch)
    st.tracker.block_at = 4

    async def scenario():
        app = st.app()
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("3", "g")
            run = app.run_state
            await wait_for(pilot, lambda: run.suspended is not None, 30, "the suspension")
            await pilot.pause()
            text = screen_text(app)
            assert "BEAM LOST" in text and "skips the pose in 0:" in text and "s skip now" in text
            assert "s Skip" in text and "w Wait" in text  # the footer offers both keys
            assert text.splitlines()[1].endswith("(s skip now, w wait longer)")  # on one line at 80
            assert "line of sight" in text
            no_class_names(text)
            # the Station screen follows the run's events: not "locked in" while the beam is blocked
            await pilot.press("1")
            await pilot.pause()
            text = screen_text(app)
            assert "BEAM LOST" in text and "locked in" not in text
            await pilot.press("3")
            await pilot.press("w")
            await wait_for(pilot, lambda: run.suspend_deadline is not None
                           and run.suspend_deadline - app.now() > 45, 10, "the longer wait")
            await pilot.press("s")
            by_operator = "skipped by the operator"
            await wait_for(pilot, lambda: any(by_operator in r.reason for r in run.rows.values()), 10,
                           "the skip")
            st.tracker.blocked = False
            await wait_for(pilot, lambda: app.screen is app.views["results"], 60, "the campaign's results")
            await pilot.press("3")
            await pilot.pause()
            assert f"{run.skipped} skipped" in screen_text(app)  # (a random pose may have no safe path)
            await press_to_close(pilot, "q")
        record = st.store.campaign(app.run_state.campaign)
        assert record.summary.skipped == run.skipped
        [pose] = [p for p in record.poses if p.status == "skipped" and by_operator in p.reason]
        assert run.rows[("calibration", pose.index)].status == "skipped"

    asyncio.run(scenario())
    st.store.close()


def test_an_unfinished_campaign_is_announced_at_start_up(tmp_path, monkeypatch):
    st = FakeStation(tmp_path, monkeypatch)
    campaign = st.store.create_campaign(st.config.as_dict(), {"type": "ur5e", "serial": st.arm.info.serial})
    st.store.save_plan(campaign, [(i, "calibration", [0.1 * i] * 6) for i in range(16)])
    for i in range(4):
        st.store.record_measurement(campaign, i, "calibration", [0.1 * i] * 6, [1.0, 0.0, 0.5])
    st.store.set_status(campaign, "interrupted")

    async def scenario():
        app = st.app()
        app.session.devices = None
        app.session.station.phase = "disconnected"
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("c")
            await wait_for(pilot, lambda: app.session.station.unfinished is not None, 10, "the check")
            await pilot.pause()
            text = screen_text(app)
            assert f"Unfinished campaign {campaign}: 4 of 16 poses measured." in text
            assert "g on the Run screen (3) resumes it" in text
            await pilot.press("3")
            await pilot.pause()
            assert f"unfinished {campaign} (4/16 measured): g resumes it" in screen_text(app)
            await press_to_close(pilot, "q")

    asyncio.run(scenario())
    st.store.close()


def test_station_readings_follow_the_run_events():
    st = StationState(phase="in run", safety="normal", lock="locked in")
    assert st.apply(Suspended(campaign="c", kind="beam_lost", message="clear the line of sight"))
    assert st.lock.startswith("BEAM LOST") and st.safety == "normal"
    assert st.apply(Resumed(campaign="c", kind="beam_lost", waited=3.0)) and st.lock == "locked in"
    assert st.apply(Suspended(campaign="c", kind="protective_stop", message="unlock it"))
    assert st.safety == "PROTECTIVE STOP"
    assert st.apply(PointMeasured(campaign="c", index=1, role="calibration", q=[0] * 6, p=[0] * 3,
                                  p_spread=[0] * 3, samples=1))
    assert (st.safety, st.lock) == ("normal", "locked in")
    assert not st.apply(PointMeasured(campaign="c", index=2, role="calibration", q=[0] * 6, p=[0] * 3,
                                      p_spread=[0] * 3, samples=1))


def test_a_campaign_left_before_its_poses_were_chosen_is_announced_with_its_bootstrap_points(
        tmp_path, monkeypatch):
    """Quit during the pose selection: the bootstrap's points are kept, and the Station screen, the
    Run screen and the resume question say so (they said "0 of ? poses measured")."""
    st = FakeStation(tmp_path, monkeypatch)
    campaign = st.store.create_campaign(st.config.as_dict(), {"type": "ur5e", "serial": st.arm.info.serial})
    st.store.save_plan(campaign, [(i, "bootstrap", [0.1 * i] * 6) for i in range(10)])
    for i in range(10):
        st.store.record_measurement(campaign, i, "bootstrap", [0.1 * i] * 6, [1.0, 0.0, 0.5])
    st.store.set_status(campaign, "interrupted")

    async def scenario():
        app = st.app()
        app.session.devices = None
        app.session.station.phase = "disconnected"
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("c")
            await wait_for(pilot, lambda: app.session.station.unfinished is not None, 10, "the check")
            await pilot.pause()
            text = screen_text(app)
            flat = " ".join(line.strip() for line in text.splitlines() if line.strip())
            assert f"Unfinished campaign {campaign}: 10 bootstrap points measured, poses not chosen yet." \
                in flat, text
            assert "0 of ?" not in flat, text
            await pilot.press("3")
            await pilot.pause()
            assert f"unfinished {campaign} (10 bootstrap measured): g resumes it" in screen_text(app)
            await pilot.press("g")
            await wait_for(pilot, lambda: isinstance(app.screen, ResumeDialog), 10, "the resume question")
            await pilot.pause()
            text = screen_text(app)
            flat = " ".join(line.strip(" █") for line in text.splitlines() if line.strip(" █"))
            assert "is unfinished (10 bootstrap points measured, poses not chosen yet)" in flat, text
            assert "0 of ?" not in flat, text
            await pilot.press("escape")
            await press_to_close(pilot, "q")

    asyncio.run(scenario())
    st.store.close()


def test_progress_words_count_poses_and_bootstrap_points_apart():
    assert progress_words(4, 16) == "4 of 16 poses measured"
    assert progress_words(4, 16, 10) == "4 of 16 poses measured (+ 10 bootstrap points)"
    assert progress_words(0, 0, 10) == "10 bootstrap points measured, poses not chosen yet"
    assert progress_words(0, 0, 1) == "1 bootstrap point measured, poses not chosen yet"
    assert progress_words(0, 0) == "nothing measured yet"
