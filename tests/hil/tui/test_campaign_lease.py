"""Issue 19, "two campaigns, one arm", in the terminal app: a run on an arm (or of a campaign) that another
live process has is refused with a clear notice — nothing moves, no campaign is created or touched —
and once it is free the run starts. On the in-process fakes (tests/hil/tui/fake_station.py)."""

from __future__ import annotations

import asyncio
import os

from hil.store import RobotIdentity
from tests.hil.tui.conftest import press_to_close, wait_for
from tests.hil.tui.fake_station import SERIAL, FakeStation

SIZE = (80, 24)


def notices(app) -> list[str]:
    said: list[str] = []
    notify = app.notify

    def record(message, *args, **kwargs):
        said.append(str(message))
        return notify(message, *args, **kwargs)

    app.notify = record
    return said


def test_a_run_on_an_arm_another_process_drives_is_refused_then_starts_once_it_is_free(tmp_path, monkeypatch):
    st = FakeStation(tmp_path, monkeypatch)
    other_station = st.config.with_overrides(station__name="cell-2").as_dict()
    other = st.store.claim_new(other_station, RobotIdentity(type="ur5e", serial=SERIAL), heartbeat=False)

    async def scenario():
        app = st.app()
        said = notices(app)
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("3", "g")
            await wait_for(pilot, lambda: any("is being driven" in s for s in said), 10, "the refusal")
            (text,) = [s for s in said if "is being driven" in s]
            assert text.startswith(f"robot {SERIAL} is being driven by campaign {other.campaign} "
                                   f"(pid {os.getpid()} on host ")
            assert not app.session.run_active and st.arm.moves == 0
            assert [c.id for c in st.store.campaigns()] == [other.campaign]  # nothing created
            other.release()  # that run ended
            await pilot.press("g")
            await wait_for(pilot, lambda: app.run_state.ended, 60, "the end of the run")
            assert app.run_state.finished.status in ("accepted", "rejected")
            await press_to_close(pilot, "q")

    asyncio.run(scenario())
    assert st.arm.moves > 0 and len(st.store.campaigns()) == 2
    st.store.close()


def test_resuming_a_campaign_another_process_runs_leaves_it_untouched(tmp_path, monkeypatch):
    """The race the question cannot close: the operator answers "resume" after another process
    took the campaign. The run is refused, the arm does not move, the campaign's status stays."""
    st = FakeStation(tmp_path, monkeypatch)
    cid = st.store.create_campaign(st.config.as_dict(), RobotIdentity(type="ur5e", serial=SERIAL))
    st.store.set_status(cid, "interrupted")
    holder = st.store.claim(cid, SERIAL, heartbeat=False)

    async def scenario():
        app = st.app()
        said = notices(app)
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("3")
            app.session.start_run(cid)
            await wait_for(pilot, lambda: any("is being run by" in s for s in said), 10, "the refusal")
            await wait_for(pilot, lambda: not app.session.run_active, 10, "the run thread to give up")
            assert any(f"campaign {cid} is being run by pid {os.getpid()}" in s for s in said), said
            assert st.arm.moves == 0
            await press_to_close(pilot, "q")

    asyncio.run(scenario())
    assert st.store.campaign(cid).summary.status == "interrupted"  # not marked failed by the refusal
    assert [c.id for c in st.store.campaigns()] == [cid]
    holder.release()
    st.store.close()
