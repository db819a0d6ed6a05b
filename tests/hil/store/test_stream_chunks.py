"""A sweep's streams in the store (`stream_chunks`, revision 0006), on SQLite and PostgreSQL alike:
each chunk committed with its event, kept once when its transaction is repeated, read back in order
for the take a `SweepSegmentDone` names, never for a take cut short."""

from __future__ import annotations

import math

import pytest

from drivers.robot.model import RobotIdentity
from hil.campaign.events import SweepChunk, SweepSegmentDone
from hil.campaign.runner import sweep_state
from hil.station.config import default_config
from hil.store import Store
from hil.store.sqlite_errors import StoreError


@pytest.fixture(params=["sqlite", "postgresql"])
def store(request, tmp_path):
    where = str(tmp_path / "hil.db") if request.param == "sqlite" else request.getfixturevalue("pg_url")
    with Store.open(where) as s:
        yield s


def chunk(cid: str, take: str, stream: str, k: int, t0: float, n: int, lost: int = -1) -> SweepChunk:
    stamps = tuple(t0 + 0.002 * i for i in range(n))
    width = 6 if stream == "joints" else 3
    values = tuple(None if i == lost else [0.1 * i + j for j in range(width)] for i in range(n))
    return SweepChunk(campaign=cid, segment=0, take=take, stream=stream, chunk=k, session="s1", count=n,
                      stamps=stamps, values=values)


def test_a_segments_chunks_are_read_back_for_the_take_its_done_event_names(store):
    cid = store.create_campaign(default_config().as_dict(), RobotIdentity("ur5e", "9999003"))
    # a first take cut short (no done event), then the whole one
    store.record_event(chunk(cid, "cut", "joints", 0, 1.0, 4))
    for event in (chunk(cid, "whole", "joints", 0, 10.0, 3), chunk(cid, "whole", "joints", 1, 10.006, 2),
                  chunk(cid, "whole", "tracker", 0, 1234.0, 3, lost=1)):
        store.record_event(event)
    store.record_event(chunk(cid, "whole", "joints", 1, 10.006, 2))  # a repeated write: kept once
    store.record_event(SweepSegmentDone(campaign=cid, segment=0, segments=1, take="whole", session="s1",
                                        joints=5, tracker=2, lost=1, breaks=1, seconds=0.01,
                                        anchor=[1234.0, 10.0]))
    t, v = store.stream_chunks(cid, 0, "whole", "joints")
    assert t == pytest.approx([10.0, 10.002, 10.004, 10.006, 10.008]) and len(v) == 5 and len(v[0]) == 6
    (seg,) = sweep_state(store, cid).values()
    assert seg.joint_q.shape == (5, 6) and seg.tracker_p.shape == (3, 3) and seg.anchor == (1234.0, 10.0)
    assert math.isnan(seg.tracker_p[1, 0]) and seg.session == "s1"
    logged = store.event_log(cid, types=("SweepChunk",))
    assert all("stamps" not in d for _, d in logged)  # the log keeps counts, the table the samples


def test_a_chunk_without_samples_or_with_mismatched_values_is_refused(store):
    cid = store.create_campaign(default_config().as_dict(), RobotIdentity("ur5e", "9999004"))
    bad = SweepChunk(campaign=cid, segment=0, take="x", stream="joints", chunk=0, count=2,
                     stamps=(1.0, 2.0), values=([0.0] * 6,))
    with pytest.raises(StoreError, match="2 stamps, 1 values"):
        store.record_event(bad)
