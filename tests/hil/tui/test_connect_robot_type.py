"""Issue 19 follow-up: the terminal app checks the controller's robot type when it connects.

Before, the Station screen's connect (c) accepted a controller reporting another robot than the
configured ``robot.type``: the screen said CONNECTED, and the mismatch showed only once a run was
started. Now connect refuses it at once — a notice and the Station screen's error naming both, no
device opened (the controller is asked what it is first), the arm's address lock let go — and a run
asked for afterwards does not move the arm.
On the in-process fakes (tests/hil/tui/fake_station.py).
"""

from __future__ import annotations

import asyncio
import dataclasses

from hil.station.devices import Devices
from hil.store import address_lock
from tests.hil.tui.conftest import press_to_close, screen_text, wait_for
from tests.hil.tui.fake_station import FakeStation
from tests.hil.tui.test_campaign_lease import notices

SIZE = (80, 24)


class CountingDevices(Devices):
    """The fake station's devices, counting how often they are closed."""

    closed = 0

    def close(self) -> None:
        type(self).closed += 1
        super().close()


def _disconnected_app(st: FakeStation):
    app = st.app()
    app.session.devices = None  # start disconnected: the test connects with c
    app.session.station.phase = "disconnected"
    return app


def test_connect_to_a_controller_of_another_robot_type_is_refused_on_the_station_screen(tmp_path,
                                                                                       monkeypatch):
    st = FakeStation(tmp_path, monkeypatch)
    st.arm.info = dataclasses.replace(st.arm.info, model="UR10e")  # the configuration says ur5e
    CountingDevices.closed = 0
    st.reconnects = [CountingDevices(st.arm, st.tracker) for _ in range(2)]  # type: ignore[arg-type]
    address = st.config.robot["address"]

    async def scenario():
        app = _disconnected_app(st)
        said = notices(app)
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("1", "c")
            await wait_for(pilot, lambda: any("cannot use this robot" in s for s in said), 10, "the refusal")
            (text,) = [s for s in said if "cannot use this robot" in s]
            assert text == (f"cannot use this robot: robot.type is ur5e but the controller at {address} "
                            "reports UR10e")
            session = app.session
            assert session.devices is None and session.station.phase == "disconnected"
            assert len(st.asked) == 1  # the controller was asked what it is
            assert len(st.reconnects) == 2 and CountingDevices.closed == 0  # and no device was opened
            with address_lock(address):  # and the arm's lock is let go
                pass
            await pilot.pause()
            shown = " ".join(screen_text(app).split())
            assert "DISCONNECTED" in shown and "cannot use this robot" in shown and "UR10e" in shown
            # a run asked for now connects again, is refused the same way, and moves nothing
            await pilot.press("3", "g")
            await wait_for(pilot, lambda: len(st.asked) == 2, 10, "the second refusal")
            await pilot.pause(0.2)
            assert not session.run_active and session.devices is None
            await press_to_close(pilot, "q")

    asyncio.run(scenario())
    assert st.arm.moves == 0 and st.store.campaigns() == []
    assert len(st.reconnects) == 2 and CountingDevices.closed == 0  # the run opened nothing either
    st.store.close()


def test_connect_to_the_configured_robot_type_connects(tmp_path, monkeypatch):
    """The same path with the controller reporting the configured robot (UR5e for ur5e) connects."""
    st = FakeStation(tmp_path, monkeypatch)

    async def scenario():
        app = _disconnected_app(st)
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("1", "c")
            await wait_for(pilot, lambda: app.session.station.phase == "connected", 10, "the connection")
            assert app.session.devices is not None and app.session.station.error == ""
            await press_to_close(pilot, "q")

    asyncio.run(scenario())
    st.store.close()
