"""Messages that arrive while the app closes (issue 29, the TUI's round 2, item 5).

The run and the station post messages from their own threads at any time. When a test ended while
the app still ran (a time-out: the simulated station starting slowly on a loaded machine), the app
closed its screens while those messages kept coming, and a handler reading the top screen raised
ScreenStackError, which run_test re-raised in place of the time-out: the emscon test's "1 of 3"
failure. A message with no screen to draw on is now drawn nowhere.
"""

from __future__ import annotations

import asyncio
import threading
import time

from hil.campaign.events import PhaseChanged, RunStarted
from hil.tui.messages import EarlierPoints, EngineEvent, StationChanged
from tests.hil.tui.test_snapshots import CID, SIZE, T0, offline_app


def test_messages_arriving_while_the_app_closes_raise_nothing():
    app = offline_app()
    stop = threading.Event()

    def station_and_run() -> None:  # as the session's threads post, until the app is gone
        while not stop.is_set():
            app.post_message(StationChanged())
            app.post_message(EngineEvent(RunStarted(campaign=CID, t=T0, robot="ur5e", station="s", poses=3)))
            app.post_message(EngineEvent(PhaseChanged(campaign=CID, t=T0, phase="measure", detail="")))
            app.post_message(EarlierPoints(CID, []))
            time.sleep(0.001)

    async def scenario() -> None:
        async with app.run_test(size=SIZE) as pilot:
            await pilot.pause()
            threading.Thread(target=station_and_run, daemon=True).start()
            await pilot.pause(0.2)
        # the body ends with the app running (as a test's time-out does): run_test closes it

    try:
        asyncio.run(scenario())  # raised ScreenStackError ("No screens on stack") before
    finally:
        stop.set()
