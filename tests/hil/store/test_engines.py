"""Issue 18: the store's contract on both engines, SQLite (one station) and PostgreSQL (a plant's fleet).

Every test of the public `Store` API here runs on an SQLite file and on a PostgreSQL database of its
own (`pg_url`): recording and reading back (floats bit-exact), idempotent writes, plans and skips, the
event log, listing and resume, read-only stores, the schema and its guards, concurrent first opens,
four stations writing at once. Then what only one engine has: a PostgreSQL server stopped, restarted
and killed under a writing store (`own_postgres`), and SQLite stores written before Alembic (versions
1 to 3, `legacy_schema`) upgraded in place.
"""

from __future__ import annotations

import json
import os
import socket
import sqlite3
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest
from alembic import command as alembic_command
from sqlalchemy import inspect

import hil.store.tables as tb
from hil.campaign.events import (
    Message,
    ModelIdentified,
    PhaseChanged,
    PointMeasured,
    PoseSkipped,
    PoseStarted,
    RunFinished,
    RunStarted,
    StateChanged,
    ValidationDone,
)
from hil.errors import FaultError, InputError
from hil.station.config import default_config
from hil.store import (
    SCHEMA_VERSION,
    PlannedPose,
    RobotIdentity,
    Store,
    StoreError,
    UnknownCampaignError,
    config_hash,
    measurement_hash,
)
from hil.store import migrate as migrate_mod
from hil.store.sqlite_errors import StoreUnavailable
from tests.hil.store.legacy_schema import make_legacy
from tests.hil.store.raw import Raw, raw

ROOT = Path(__file__).resolve().parents[3]
ROBOT = RobotIdentity(type="ur5e", serial="20235500123", model="UR5e", software="5.15.0")
T0 = 1_700_000_000.0  # 2023-11-14: campaign ids of T0 + a few seconds share their date in any zone
# floats a lossy text round trip would change: 0.1 + 0.2, a third, the next double after 1, -0.0, the
# smallest subnormal, the largest double
AWKWARD_Q = (0.1 + 0.2, 1 / 3, float(np.nextafter(1.0, 2.0)), -0.0, 5e-324, 1.7976931348623157e308)


def cfg(name: str = "cell-1", address: str = "10.0.0.1", **overrides: Any) -> dict[str, Any]:
    data = default_config().as_dict()
    data["station"]["name"] = name
    data["robot"]["address"] = address
    for dotted, value in overrides.items():
        section, key = dotted.split("__")
        data[section][key] = value
    return data


def plan(n_cal: int = 4, n_val: int = 2) -> list[tuple[int, str, list[float]]]:
    rows = [(i, "calibration", [0.1 * i, -1.0, 1.0, 0.0, 0.5, 0.0]) for i in range(n_cal)]
    rows += [(n_cal + i, "validation", [0.2 * i, -1.2, 1.1, 0.1, 0.5, 0.0]) for i in range(n_val)]
    return rows


def bits(values: Any) -> bytes:
    """The exact IEEE 754 bytes of a float array: equal only if every bit is (so -0.0 != 0.0)."""
    return np.asarray(values, dtype=np.float64).tobytes()


def model_doc(rms: float = 20e-6) -> dict[str, Any]:
    return {"format": "hil-model/1", "robot": "ur5e", "fit": {"rms": rms, "max": 3 * rms},
            "parameters": [{"name": "a", "value": 1 / 3, "std": 1e-6}]}


def count(store: Store, sql: str, params: tuple[Any, ...] = ()) -> int:
    return int(raw(store).execute(sql, params).fetchone()[0])


def pg_tables(url: str) -> set[str]:
    """The tables of a PostgreSQL database, seen from outside the store (plain psycopg)."""
    with psycopg.connect(url, connect_timeout=5) as conn:
        return {r[0] for r in conn.execute("SELECT tablename FROM pg_tables WHERE schemaname = 'public'")}


@pytest.fixture(params=["sqlite", "postgresql"])
def location(request, tmp_path) -> str:
    """Where the store lives: an SQLite file (not there yet), or a fresh, empty PostgreSQL database."""
    if request.param == "sqlite":
        return str(tmp_path / "data" / "hil.db")
    return str(request.getfixturevalue("pg_url"))


@pytest.fixture
def store(location):
    with Store.open(location) as s:
        yield s


@pytest.fixture
def upgrades(monkeypatch) -> list[str]:
    """Every Alembic upgrade run (the revision it aimed at), wherever it comes from."""
    calls: list[str] = []
    real = alembic_command.upgrade

    def counting(config, revision, *args, **kwargs):
        calls.append(revision)
        return real(config, revision, *args, **kwargs)

    monkeypatch.setattr(alembic_command, "upgrade", counting)
    return calls


# --- 1. recording and reading back --------------------------------------------------------------
def test_a_campaign_is_recorded_and_read_back_bit_exactly(location):
    rng = np.random.default_rng(18)
    tracker = rng.normal(scale=1e-5, size=(5, 3)) + np.array([1.234567890123456, -0.1, 2.0])
    joints = rng.normal(size=(10, 6)) / 3
    p0 = tracker.mean(axis=0)
    selection = {"method": "tabu", "index": "O1", "value": 1.5, "tiny": 1e-300, "third": 1 / 3}
    with Store.open(location) as s:
        cid = s.create_campaign(cfg(), ROBOT, selection)
        # the same arm under another configuration: one robot row, following its controller
        other = s.create_campaign(cfg("cell-2"), RobotIdentity("ur5e", ROBOT.serial, "UR5e", "5.16.0"))
        unknown = s.create_campaign(cfg("cell-3"))  # serial unknown: no robot row
        s.save_plan(cid, plan())
        mid = s.record_measurement(cid, 0, "calibration", AWKWARD_Q, p0, q_spread=[1e-6 / 3] * 6,
                                   p_spread=[2e-6, 0.0, 7e-7], samples=5, deviation=1.2345678901234e-4,
                                   t=T0 + 0.123456789, tracker_samples=tracker, joint_samples=joints)
        first1 = s.record_measurement(cid, 1, "calibration", [0.1, -1, 1, 0, 0.5, 0], [1.0, 2.0, 3.0],
                                      t=T0 + 1)
        s.record_measurement(cid, 4, "validation", [0.0, -1.2, 1.1, 0.1, 0.5, 0.0], [4.0, 5.0, 6.0],
                             t=T0 + 2)
        latest1 = s.record_measurement(cid, 1, "calibration", [0.1, -1, 1, 0, 0.5, 0],
                                       [1.0, 2.0, 3.5], t=T0 + 3)  # measured again: the latest counts
    with Store.open(location, create=False) as s:
        rec = s.campaign(cid)
        assert rec.config == cfg() and rec.config_hash == config_hash(cfg())
        assert rec.plan == selection and bits(rec.plan["third"]) == bits(1 / 3)
        assert rec.robot == RobotIdentity("ur5e", ROBOT.serial, "UR5e", "5.16.0")  # updated by `other`
        assert s.campaign(other).robot == rec.robot and s.campaign(unknown).robot == RobotIdentity("ur5e")
        assert count(s, "SELECT count(*) FROM robots") == 1
        assert count(s, "SELECT count(*) FROM stations") == 3
        summary = rec.summary
        assert (summary.station, summary.robot, summary.serial, summary.status) == (
            "cell-1", "ur5e", ROBOT.serial, "created")
        assert (summary.planned, summary.measured, summary.skipped) == (6, 3, 0)
        assert [(p.index, p.status) for p in rec.poses] == [
            (0, "measured"), (1, "measured"), (2, "planned"), (3, "planned"), (4, "measured"),
            (5, "planned")]
        # every row, in recording order; the latest per pose, by pose index
        assert [(m.index, m.id) for m in s.measurements(cid)] == [
            (0, mid), (1, first1), (4, rec.measurements[2].id), (1, latest1)]
        assert [m.index for m in s.measurements(cid, role="validation")] == [4]
        latest = s.measured_poses(cid)
        assert list(latest) == [0, 1, 4] and latest[1].id == latest1 and latest[1].p == (1.0, 2.0, 3.5)
        m = latest[0]
        assert m.id == mid and m.role == "calibration" and m.samples == 5
        assert bits(m.q) == bits(AWKWARD_Q) and bits(m.p) == bits(p0)
        assert bits(m.q_spread) == bits([1e-6 / 3] * 6) and bits(m.p_spread) == bits([2e-6, 0.0, 7e-7])
        assert bits(m.deviation) == bits(1.2345678901234e-4) and bits(m.t) == bits(T0 + 0.123456789)
        assert latest[1].q_spread is None and latest[1].deviation is None
        samples = s.samples(mid)
        assert bits(samples["tracker"]) == bits(tracker) and bits(samples["joints"]) == bits(joints)
        assert s.samples(latest1) == {"tracker": [], "joints": []}
        q, p = s.arrays(cid)  # calibration by default
        assert bits(q[0]) == bits(AWKWARD_Q) and bits(p) == bits([p0, [1.0, 2.0, 3.5]])
        qv, pv = s.arrays(cid, "validation")
        assert qv.shape == (1, 6) and pv.tolist() == [[4.0, 5.0, 6.0]]
        assert s.arrays(cid, "bootstrap")[0].shape == (0, 6)
        assert s.arrays(other)[1].shape == (0, 3)


# --- 2. idempotence ---------------------------------------------------------------------------------
def test_every_write_is_idempotent(store):
    cid = store.create_campaign(cfg(), ROBOT)
    q, p = [0.3] * 6, [1.0, 2.0, 3.0]
    tracker = [[1.0, 2.0, 3.0], [1.0, 2.0, 3.0 + 1e-9]]
    a = store.record_measurement(cid, 3, "calibration", q, p, samples=2, t=T0, tracker_samples=tracker)
    b = store.record_measurement(cid, 3, "calibration", q, p, samples=2, t=T0, tracker_samples=tracker)
    assert a == b and [m.id for m in store.measurements(cid)] == [a]
    assert bits(store.samples(a)["tracker"]) == bits(tracker)  # not doubled
    # the direct call with raw samples, then its PointMeasured with the same t: one row, spreads kept
    c = store.record_measurement(cid, 5, "calibration", q, p, q_spread=[1e-6] * 6, samples=2,
                                 t=T0 + 5, tracker_samples=tracker)
    seq = store.record_event(PointMeasured(campaign=cid, t=T0 + 5, index=5, role="calibration", q=q,
                                           p=p, p_spread=[0.0] * 3, samples=2))
    assert seq == 1 and [m.id for m in store.measurements(cid)] == [a, c]
    assert store.measured_poses(cid)[5].q_spread == (1e-6,) * 6
    assert count(store, "SELECT count(*) FROM measurements") == 2
    assert count(store, "SELECT count(*) FROM samples") == 4
    # the event alone at another t is another measurement (a re-measurement)
    store.record_event(PointMeasured(campaign=cid, t=T0 + 6, index=5, role="calibration", q=q, p=p,
                                     p_spread=[0.0] * 3, samples=2))
    assert len(store.measurements(cid)) == 3
    # the same model document (keys in any order), directly or by its event: one row, one id
    doc = model_doc()
    model = store.save_model(cid, doc)
    assert store.save_model(cid, dict(reversed(list(doc.items())))) == model
    store.record_event(ModelIdentified(campaign=cid, rms=20e-6, max=60e-6, iterations=3, rejected=[],
                                       model=doc))
    assert [m.id for m in store.campaign(cid).models] == [model]
    assert store.save_model(cid, model_doc(21e-6)) != model
    # the same validation: one row; a different verdict is another
    before, after = {"count": 3, "rms": 1e-3}, {"count": 3, "rms": 2e-5}
    v = store.save_validation(cid, before, after, True, model=model, details={"AP": 1e-5})
    assert store.save_validation(cid, before, after, True, model=model, details={"AP": 1e-5}) == v
    assert store.save_validation(cid, before, after, False, model=model, details={"AP": 1e-5}) != v
    assert count(store, "SELECT count(*) FROM validations") == 2


# --- 3. plans and skips ---------------------------------------------------------------------------
def test_save_plan_replaces_planned_poses_only_and_skips_follow_their_rules(store):
    cid = store.create_campaign(cfg(), ROBOT)
    store.save_plan(cid, [(i, "bootstrap", [0.1 * i] * 6) for i in range(3)])
    store.record_measurement(cid, 0, "bootstrap", [0] * 6, [1, 1, 1], t=T0)
    store.record_skip(cid, 2, "bootstrap", "no line of sight")
    store.save_plan(cid, [PlannedPose(1, "calibration", (0.25,) * 6), (3, "validation", [0.3] * 6)],
                    plan={"method": "exchange"})
    store.save_plan(cid, [(0, "bootstrap", [0.0] * 6), (2, "bootstrap", [0.2] * 6)])  # unchanged: fine
    assert [(p.index, p.role, p.target[0], p.status, p.reason) for p in store.poses(cid)] == [
        (0, "bootstrap", 0.0, "measured", ""), (1, "calibration", 0.25, "planned", ""),
        (2, "bootstrap", 0.2, "skipped", "no line of sight"), (3, "validation", 0.3, "planned", "")]
    assert store.campaign(cid).plan == {"method": "exchange"}
    for pose, status in ((0, "measured"), (2, "skipped")):
        with pytest.raises(StoreError, match=f"pose {pose} is already {status}"):
            store.save_plan(cid, [(pose, "bootstrap", [0.5] * 6)])
        with pytest.raises(StoreError, match=f"pose {pose} is already {status}"):
            store.save_plan(cid, [(pose, "calibration", [0.2 * pose] * 6)])
    with pytest.raises(StoreError, match="role"):
        store.save_plan(cid, [(4, "warmup", [0] * 6)])
    with pytest.raises(StoreError, match="6 numbers"):
        store.save_plan(cid, [(4, "calibration", [0] * 5)])
    with pytest.raises(StoreError, match="no campaign"):
        store.save_plan("nope", [(0, "calibration", [0] * 6)])
    assert len(store.poses(cid)) == 4  # a refused plan changed nothing
    # skips: planned -> skipped; a measured pose stays measured; a pose not in the plan is refused
    store.record_skip(cid, 1, "calibration", "unreachable")
    store.record_skip(cid, 0, "bootstrap", "too late")
    with pytest.raises(StoreError, match="cannot skip pose 9: it is not in the plan"):
        store.record_skip(cid, 9, "calibration", "?")
    with pytest.raises(StoreError, match="no campaign"):
        store.record_skip("nope", 1, "calibration", "?")
    statuses = {p.index: (p.status, p.reason) for p in store.poses(cid)}
    assert statuses[0] == ("measured", "") and statuses[1] == ("skipped", "unreachable")
    assert [p.index for p in store.pending_poses(cid)] == [3]
    assert [p.index for p in store.pending_poses(cid, include_skipped=True)] == [1, 2, 3]
    # a skipped pose measured after all (a resume retrying skipped poses) is measured
    store.record_measurement(cid, 1, "calibration", [0.25] * 6, [2, 2, 2], t=T0 + 1)
    assert {p.index: (p.status, p.reason) for p in store.poses(cid)}[1] == ("measured", "")
    summary = store.campaign(cid).summary
    assert (summary.planned, summary.measured, summary.skipped) == (2, 1, 0)  # bootstrap not counted


# --- 4. the event log -----------------------------------------------------------------------------
def test_events_are_numbered_per_campaign_and_a_dead_owner_reads_as_interrupted(store):
    cid = store.create_campaign(cfg(), ROBOT)
    other = store.create_campaign(cfg("cell-2"))
    store.save_plan(cid, plan(2, 1))
    events = [
        RunStarted(campaign=cid, robot="ur5e", station="cell-1", poses=3),
        StateChanged(campaign=cid, state="running", previous="idle"),
        PhaseChanged(campaign=cid, phase="measure"),
        PoseStarted(campaign=cid, index=0, role="calibration", target=[0.0, -1, 1, 0, 0.5, 0]),
        PointMeasured(campaign=cid, index=0, role="calibration", q=[0.0] * 6, p=[1, 2, 3],
                      p_spread=[1e-6] * 3, samples=5),
        PoseSkipped(campaign=cid, index=1, role="calibration", reason="no line of sight"),
    ]
    seqs, other_seqs = [], []
    for ev in events:  # another campaign's log interleaved: numbered on its own
        seqs.append(store.record_event(ev))
        other_seqs.append(store.record_event(PhaseChanged(campaign=other, phase="x")))
    assert seqs == other_seqs == [1, 2, 3, 4, 5, 6]
    log = store.event_log(cid)
    assert [seq for seq, _ in log] == [1, 2, 3, 4, 5, 6]
    assert [d["event"] for _, d in log] == [e.name for e in events]
    assert [seq for seq, _ in store.event_log(cid, after=4)] == [5, 6]
    assert store.event_log(cid, after=6) == [] and store.event_log("nope") == []
    owner = log[0][1]["owner"]  # RunStarted: who runs it
    assert (owner["pid"], owner["host"]) == (os.getpid(), socket.gethostname())
    assert store.events(cid) == events  # read back as the same events (the owner is not a field)
    assert store.events(cid, after=5) == events[-1:]
    assert store.campaign(cid).event_counts == {e.name: 1 for e in events}
    assert store.campaigns(station="cell-1")[0].status == "running"  # its process (us) is alive

    # the run's process is gone (fake: a pid that has ended): listed as interrupted, file unchanged
    done = subprocess.Popen(["true"])
    done.wait(timeout=10)
    data = json.loads(raw(store).execute("SELECT data FROM events WHERE campaign = ? AND seq = 1",
                                         (cid,)).fetchone()[0])
    data["owner"] = {**data["owner"], "pid": done.pid, "started": None}
    raw(store).execute("UPDATE events SET data = ? WHERE campaign = ? AND seq = 1", (json.dumps(data), cid))
    (summary,) = store.campaigns(station="cell-1")
    assert summary.status == "interrupted" and not summary.finished
    record = store.campaign(cid)
    assert record.summary.status == "interrupted" and "process ended" in record.detail
    assert raw(store).execute("SELECT status FROM campaigns WHERE id = ?", (cid,)).fetchone()[0] == "running"
    assert store.find_resumable(cfg(), ROBOT.serial) == cid
    # a finished run stays what it is, whoever recorded it
    assert store.record_event(RunFinished(campaign=cid, status="accepted", detail="ok")) == 7
    assert store.campaigns(station="cell-1")[0].status == "accepted"


def test_threads_appending_to_one_campaign_log_get_one_gapless_sequence(store):
    """A `Store` may be shared between threads (`hil.store.transactions`): appends to one campaign's log made
    at the same moment are numbered one after the other, as SQLite's write lock does it."""
    cid = store.create_campaign(cfg(), ROBOT)
    threads_n, each = 4, 15
    barrier = threading.Barrier(threads_n)
    seqs: list[int] = []
    errors: list[BaseException] = []

    def append(k: int) -> None:
        try:
            barrier.wait(timeout=10)
            for i in range(each):
                seqs.append(store.record_event(Message(campaign=cid, level="info", text=f"{k}-{i}")))
        except BaseException as exc:
            errors.append(exc)

    threads = [threading.Thread(target=append, args=(k,), daemon=True) for k in range(threads_n)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    assert not any(t.is_alive() for t in threads)
    assert [str(e) for e in errors] == []
    assert sorted(seqs) == list(range(1, threads_n * each + 1))
    log = store.event_log(cid)
    assert [seq for seq, _ in log] == sorted(seqs)
    texts = sorted(f"{k}-{i}" for k in range(threads_n) for i in range(each))
    assert sorted(d["text"] for _, d in log) == texts


# --- 5. listing, ids, resume ----------------------------------------------------------------------
def test_listing_id_resolution_and_resume(store):
    with pytest.raises(UnknownCampaignError, match="no campaigns yet"):
        store.resolve_id("last")
    ids = [store.create_campaign(cfg("a" if i % 2 else "b"), ROBOT, now=T0 + i) for i in range(5)]
    assert [c.id for c in store.campaigns()] == ids[::-1]
    assert [c.id for c in store.campaigns(2)] == ids[:-3:-1]
    assert [c.id for c in store.campaigns(None)] == ids[::-1]
    assert [c.id for c in store.campaigns(station="a")] == [ids[3], ids[1]]
    assert [c.id for c in store.campaigns(1, station="b")] == [ids[4]]
    assert store.campaigns(station="nowhere") == []
    assert store.resolve_id("last") == store.resolve_id("latest") == ids[-1]
    assert store.resolve_id(ids[2]) == ids[2]
    assert store.resolve_id(ids[2][:15]) == ids[2]  # date and time: unique here
    with pytest.raises(UnknownCampaignError, match="several"):
        store.resolve_id(ids[0][:8])
    for text in ("1999", "%", "_", ids[2][:9] + "%", ""):  # LIKE's wildcards are plain characters
        with pytest.raises(UnknownCampaignError, match="no campaign"):
            store.resolve_id(text)
    # same creation second: the id breaks the tie, on both engines alike
    twins = [store.create_campaign(cfg("c"), ROBOT, now=T0 + 100) for _ in range(3)]
    assert [c.id for c in store.campaigns(station="c")] == sorted(twins, reverse=True)

    # resume: by serial, or without one by the robot's address; never a finished campaign
    s1, s2 = "2023550001", "2023550002"
    base = cfg("r", "10.0.0.1")
    arm1 = store.create_campaign(base, RobotIdentity("ur5e", s1), now=T0 + 200)
    arm2 = store.create_campaign(base, RobotIdentity("ur5e", s2), now=T0 + 201)
    at7 = store.create_campaign(cfg("r", "10.0.0.7"), now=T0 + 202)
    at8 = store.create_campaign(cfg("r", "10.0.0.8"), now=T0 + 203)
    assert store.find_resumable(base, s1) == arm1
    assert store.find_resumable(cfg("r", "10.9.9.9"), s1) == arm1  # the serial, not the address
    assert store.find_resumable(base, s2) == arm2
    assert store.find_resumable(base, "2023550003") is None  # never another arm's campaign
    assert store.find_resumable(cfg("r", "10.0.0.7")) == at7
    assert store.find_resumable(cfg("r", "10.0.0.8")) == at8
    assert store.find_resumable(base) == arm2  # the newest at that address
    assert store.find_resumable(cfg("r", "10.0.0.9")) is None
    assert store.find_resumable(cfg("r", "10.0.0.7", tracker__url="tcp://t:1")) == at7
    assert store.find_resumable(cfg("r", "10.0.0.7", campaign__samples=9)) is None
    assert store.find_resumable(config_sha256=config_hash(cfg("r", "10.0.0.8"))) == at8
    store.set_status(at8, "failed", "connection lost")  # a hardware fault: resumable
    assert store.find_resumable(cfg("r", "10.0.0.8")) == at8
    for status in ("accepted", "rejected", "aborted"):
        store.set_status(at8, status)
        assert store.find_resumable(cfg("r", "10.0.0.8")) is None
    store.record_event(RunFinished(campaign=arm1, status="accepted"))
    assert store.find_resumable(base, s1) is None
    assert store.campaign(at7).summary.status == "created"


# --- 6. read-only stores --------------------------------------------------------------------------
def test_a_readonly_store_reads_and_refuses_every_write(location):
    with Store.open(location) as s:
        cid = s.create_campaign(cfg(), ROBOT)
        s.save_plan(cid, plan(2, 0))
        mid = s.record_measurement(cid, 0, "calibration", [0.0] * 6, [1.0, 2.0, 3.0], t=T0,
                                   tracker_samples=[[1.0, 2.0, 3.0]])
    with Store.open(location, readonly=True) as ro:
        assert [c.id for c in ro.campaigns()] == [cid] and ro.resolve_id("last") == cid
        assert ro.measured_poses(cid)[0].id == mid and len(ro.samples(mid)["tracker"]) == 1
        writes = [
            ("create a campaign", lambda: ro.create_campaign(cfg(), ROBOT)),
            ("create a campaign", lambda: ro.claim_new(cfg(), ROBOT, heartbeat=False)),
            (f"claim campaign {cid}", lambda: ro.claim(cid, ROBOT.serial, heartbeat=False)),
            ("save the plan", lambda: ro.save_plan(cid, [(5, "calibration", [0.0] * 6)])),
            ("record the measurement of pose 1", lambda: ro.record_measurement(
                cid, 1, "calibration", [0.0] * 6, [1.0, 2.0, 3.0], t=T0 + 1)),
            ("record the skip of pose 1", lambda: ro.record_skip(cid, 1, "calibration", "x")),
            ("record RunStarted", lambda: ro.record_event(
                RunStarted(campaign=cid, robot="ur5e", station="cell-1", poses=2))),
            ("save the model", lambda: ro.save_model(cid, model_doc())),
            ("save the validation", lambda: ro.save_validation(cid, {"rms": 1.0}, {"rms": 0.1}, True)),
            ("set the status", lambda: ro.set_status(cid, "aborted")),
            ("record the controller's calibration", lambda: ro.set_controller(ROBOT.serial, {"dh": []})),
        ]
        for what, write in writes:
            with pytest.raises(StoreError, match=f"opened read-only: cannot {what}"):
                write()
        with pytest.raises(StoreError, match="read-only"), ro.writing("test"):
            pass
        # and the database itself refuses, should a write slip through a reading connection
        with pytest.raises(StoreError), ro.reading() as conn:
            Raw(conn).execute("UPDATE campaigns SET status = 'aborted'")
    with Store.open(location) as s:
        assert [c.status for c in s.campaigns()] == ["created"]
        assert count(s, "SELECT count(*) FROM measurements") == 1
        assert count(s, "SELECT count(*) FROM events") == 0
        assert count(s, "SELECT count(*) FROM leases") == 0


def test_a_readonly_open_never_creates_a_store(location, tmp_path):
    if location.startswith("postgresql"):
        with pytest.raises(InputError, match="a PostgreSQL database, but not a hil store"):
            Store.open(location, readonly=True)
        assert pg_tables(location) == set()
        return
    path = Path(location)
    with pytest.raises(InputError, match="no such database"):
        Store.open(path, readonly=True)
    assert not path.exists() and not path.parent.exists()
    empty = tmp_path / "empty.db"
    empty.touch()
    with pytest.raises(InputError, match="empty: not a hil store"):
        Store.open(empty, readonly=True)
    assert empty.stat().st_size == 0 and sorted(p.name for p in tmp_path.iterdir()) == ["empty.db"]


# --- 7. the schema and its guards -----------------------------------------------------------------
def test_a_fresh_database_has_the_whole_schema_at_the_head_revision(store, location):
    assert count(store, "SELECT count(*) FROM alembic_version") == 1
    assert raw(store).execute("SELECT version_num FROM alembic_version").fetchone()[0] == "0006"
    assert migrate_mod.HEAD == migrate_mod.script_head() == "0006" and SCHEMA_VERSION == 6
    with store.reading() as conn:
        inspector = inspect(conn)
        assert set(inspector.get_table_names()) == set(tb.metadata.tables) | {"alembic_version"}
        for name, table in tb.metadata.tables.items():
            assert {c["name"] for c in inspector.get_columns(name)} == set(table.columns.keys()), name
            assert {i.name for i in table.indexes} <= {i["name"] for i in inspector.get_indexes(name)}, name
    if not location.startswith("postgresql"):
        assert count(store, "PRAGMA user_version") == SCHEMA_VERSION


def test_a_newer_database_is_refused(location):
    with Store.open(location) as s:
        raw(s).execute("UPDATE alembic_version SET version_num = '0099'")
    with pytest.raises(InputError, match=r"schema revision 0099 is newer than this hil supports \(0006\)"):
        Store.open(location)
    with pytest.raises(InputError, match="newer"):
        Store.open(location, readonly=True)
    if location.startswith("postgresql"):
        with psycopg.connect(location, connect_timeout=5) as conn:
            assert conn.execute("SELECT version_num FROM alembic_version").fetchone() == ("0099",)
    else:
        with sqlite3.connect(location) as conn:
            assert conn.execute("SELECT version_num FROM alembic_version").fetchone() == ("0099",)


def test_a_store_at_the_head_is_opened_without_importing_alembic(location):
    """Alembic is for changing a schema: opening a store already at the head — to read it, or to write
    into it — reads its revision without importing Alembic (a third of ``hil history``'s start-up)."""
    Store.open(location).close()
    code = ("import sys\nfrom hil.store import Store\n"
            f"Store.open({location!r}, readonly=True).close()\nStore.open({location!r}).close()\n"
            "print('alembic' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert (out.returncode, out.stdout.strip()) == (0, "False"), out.stderr


def test_a_store_with_two_revisions_is_refused(location):
    """hil's revisions are one line: two rows in alembic_version are not a store it wrote (bad input,
    named), whether opened to read or to write."""
    with Store.open(location) as s:
        raw(s).execute("INSERT INTO alembic_version (version_num) VALUES ('0004')")
    for readonly in (False, True):
        with pytest.raises(InputError, match=r"alembic_version holds 2 revisions \(000[46], 000[46]\)"):
            Store.open(location, readonly=readonly)


def test_a_database_with_a_campaigns_table_but_no_revision_is_refused_untouched(location):
    if location.startswith("postgresql"):
        with psycopg.connect(location, connect_timeout=5, autocommit=True) as conn:
            conn.execute("CREATE TABLE campaigns (id text PRIMARY KEY, note text)")
            conn.execute("INSERT INTO campaigns VALUES ('mine', 'not hil''s')")
        with pytest.raises(InputError, match="tables named like hil's, but not a hil store"):
            Store.open(location)
        tables = pg_tables(location)
        with psycopg.connect(location, connect_timeout=5) as conn:
            rows = conn.execute("SELECT * FROM campaigns").fetchall()
    else:
        Path(location).parent.mkdir(parents=True)
        with sqlite3.connect(location) as conn:
            conn.execute("CREATE TABLE campaigns (id text PRIMARY KEY, note text)")
            conn.execute("INSERT INTO campaigns VALUES ('mine', 'not hil''s')")
        conn.close()
        with pytest.raises(InputError, match="an SQLite database, but not a hil store"):
            Store.open(location)
        with sqlite3.connect(location) as conn:
            tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
            rows = conn.execute("SELECT * FROM campaigns").fetchall()
            assert conn.execute("PRAGMA user_version").fetchone() == (0,)
        conn.close()
    assert tables == {"campaigns"} and rows == [("mine", "not hil's")]


# --- 8. first opens racing ------------------------------------------------------------------------
def test_two_stores_opened_by_four_threads_at_once_upgrade_exactly_once(location, upgrades):
    stores = [Store(location), Store(location)]
    barrier = threading.Barrier(4)
    errors: list[BaseException] = []

    def opener(i: int) -> None:
        try:
            barrier.wait(timeout=10)
            stores[i % 2].connect()
        except BaseException as exc:
            errors.append(exc)

    threads = [threading.Thread(target=opener, args=(i,), daemon=True) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    try:
        assert not any(t.is_alive() for t in threads)
        assert errors == []
        assert upgrades == ["0006"]
        cid = stores[0].create_campaign(cfg(), ROBOT)
        assert [c.id for c in stores[1].campaigns()] == [cid]
        assert raw(stores[1]).execute("SELECT version_num FROM alembic_version").fetchall() == [("0006",)]
    finally:
        for s in stores:
            s.close()


# --- 9. stations writing at once --------------------------------------------------------------------
STATIONS, POSES, SAMPLED_EVERY = 4, 60, 10

STATION = r"""
import json, os, sys, time
import numpy as np
from hil.campaign.events import PointMeasured, PoseStarted, RunFinished, RunStarted
from hil.station.config import default_config
from hil.store import RobotIdentity, Store

location, k, n, every, go = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
name, serial = f"station-{k}", f"2023550{k:03d}"
config = default_config().as_dict()
config["station"]["name"] = name
store = Store.open(location)
open(f"{go}.{k}", "w").close()  # ready
deadline = time.monotonic() + 30
while not os.path.exists(go):
    if time.monotonic() > deadline:
        sys.exit("never told to go")
    time.sleep(0.002)
began = time.time()
lease = store.claim_new(config, RobotIdentity("ur5e", serial, "UR5e", "5.15.0"), {"station": k})
cid = lease.campaign
store.record_event(RunStarted(campaign=cid, robot="ur5e", station=name, poses=n))
ids = {}
for i in range(n):
    rng = np.random.default_rng([k, i])
    q, tracker = (rng.normal(size=6) / 3).tolist(), rng.normal(size=(5, 3)) / 7
    p = tracker.mean(axis=0).tolist()
    t = 1.7e9 + i + k / 10
    store.record_event(PoseStarted(campaign=cid, t=t, index=i, role="calibration", target=q))
    if i % every == 0:
        ids[i] = store.record_measurement(cid, i, "calibration", q, p, samples=5, t=t + 0.5,
                                          tracker_samples=tracker)
    store.record_event(PointMeasured(campaign=cid, t=t + 0.5, index=i, role="calibration", q=q, p=p,
                                     p_spread=[1e-6] * 3, samples=5))
store.record_event(RunFinished(campaign=cid, status="accepted", detail=name))
ended = time.time()
lease.release()
store.close()
print(json.dumps({"campaign": cid, "name": name, "serial": serial, "ids": ids, "began": began,
                  "ended": ended}), flush=True)
"""


def station_values(k: int, i: int) -> tuple[list[float], np.ndarray]:
    """What station `k`'s script measures at pose `i` (the same generator, the same numbers)."""
    rng = np.random.default_rng([k, i])
    return (rng.normal(size=6) / 3).tolist(), rng.normal(size=(5, 3)) / 7


def test_four_stations_write_at_once_and_every_row_is_accounted_for(location, tmp_path):
    Store.open(location).close()  # the schema first: the race of first opens is the test above
    go = tmp_path / "go"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    spawned = time.monotonic()
    procs = [subprocess.Popen([sys.executable, "-c", STATION, location, str(k), str(POSES),
                               str(SAMPLED_EVERY), str(go)], cwd=ROOT, env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for k in range(STATIONS)]
    try:
        deadline = time.monotonic() + 60
        while not all(Path(f"{go}.{k}").exists() for k in range(STATIONS)):
            assert all(p.poll() is None for p in procs), [p.communicate(timeout=10) for p in procs]
            assert time.monotonic() < deadline, "the stations did not open the store"
            time.sleep(0.01)
        started = time.monotonic()
        go.touch()
        results = []
        for proc in procs:
            out, err = proc.communicate(timeout=60)
            assert proc.returncode == 0, err
            results.append(json.loads(out))
        elapsed = time.monotonic() - started
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait(timeout=10)
    print(f"{location.split(':')[0]}: {STATIONS} stations up in {started - spawned:.2f} s, "
          f"{POSES} poses each in {elapsed:.2f} s")
    # they did run at the same time: every station started before any finished
    assert max(r["began"] for r in results) < min(r["ended"] for r in results)
    n_events = 2 + 2 * POSES
    sampled = list(range(0, POSES, SAMPLED_EVERY))
    with Store.open(location) as s:
        summaries = {c.id: c for c in s.campaigns(None)}
        assert sorted(summaries) == sorted(r["campaign"] for r in results)
        for k, r in enumerate(results):
            cid = r["campaign"]
            summary = summaries[cid]
            assert (summary.station, summary.serial, summary.status) == (r["name"], r["serial"], "accepted")
            assert (summary.planned, summary.measured) == (POSES, POSES)
            rows = s.measurements(cid)
            assert sorted(m.index for m in rows) == list(range(POSES))  # each once
            assert {str(i): m.id for i, m in s.measured_poses(cid).items() if i in sampled} == r["ids"]
            for m in rows:
                q, tracker = station_values(k, m.index)
                assert bits(m.q) == bits(q) and bits(m.p) == bits(tracker.mean(axis=0))
                if m.index in sampled:
                    assert bits(s.samples(m.id)["tracker"]) == bits(tracker)
            log = s.event_log(cid)
            assert [seq for seq, _ in log] == list(range(1, n_events + 1))  # no gap, no repeat
            kinds = [d["event"] for _, d in log]
            assert kinds[0] == "RunStarted" and kinds[-1] == "RunFinished"
            assert kinds.count("PoseStarted") == kinds.count("PointMeasured") == POSES
        assert count(s, "SELECT count(*) FROM measurements") == STATIONS * POSES
        assert count(s, "SELECT count(*) FROM samples") == STATIONS * len(sampled) * 5
        assert count(s, "SELECT count(*) FROM events") == STATIONS * n_events
        assert count(s, "SELECT count(*) FROM poses WHERE status = 'measured'") == STATIONS * POSES
        assert raw(s).execute("SELECT campaign, pose, count(*) FROM measurements GROUP BY campaign, pose "
                              "HAVING count(*) > 1").fetchall() == []
        assert count(s, "SELECT count(*) FROM stations") == STATIONS
        assert count(s, "SELECT count(*) FROM robots") == STATIONS
        assert s.leases() == []


# --- 10. a lost link to PostgreSQL ------------------------------------------------------------------
def _measure(store: Store, cid: str, i: int) -> int:
    return store.record_measurement(cid, i, "calibration", [i / 3] * 6, [1.0, 2.0, i / 7], samples=2,
                                    t=T0 + i, tracker_samples=[[1.0, 2.0, i / 7]] * 2)


def _check_measured(store: Store, cid: str, n: int) -> None:
    rows = store.measurements(cid)
    assert sorted(m.index for m in rows) == list(range(n))  # every one, once
    for m in rows:
        assert bits(m.p) == bits([1.0, 2.0, m.index / 7]) and len(store.samples(m.id)["tracker"]) == 2


def test_a_write_waits_for_a_restarted_server_then_succeeds(own_postgres):
    url = own_postgres.create_database("lost_link")
    with Store.open(url) as store:
        told: list[str | None] = []
        store.on_outage = told.append
        cid = store.create_campaign(cfg(), ROBOT)
        for i in range(5):
            _measure(store, cid, i)
        own_postgres.stop()
        failures: list[BaseException] = []

        def restart() -> None:
            try:
                time.sleep(2.0)
                own_postgres.start()
            except BaseException as exc:
                failures.append(exc)

        restarter = threading.Thread(target=restart, daemon=True)
        restarter.start()
        began = time.monotonic()
        mid = _measure(store, cid, 5)  # blocks until the server is back
        waited = time.monotonic() - began
        restarter.join(timeout=60)
        assert not restarter.is_alive() and failures == []
        assert 1.5 < waited < 30
        assert len(told) == 2 and told[1] is None
        assert told[0] is not None and "database link lost" in told[0] and "waiting up to 600 s" in told[0]
        _check_measured(store, cid, 6)
        assert store.measured_poses(cid)[5].id == mid
        assert count(store, "SELECT count(*) FROM measurements WHERE pose = 5") == 1


def test_a_server_gone_longer_than_the_outage_timeout_stops_the_write(own_postgres):
    url = own_postgres.create_database("gone")
    store = Store(url, outage_timeout=1.0).connect()
    try:
        told: list[str | None] = []
        store.on_outage = told.append
        cid = store.create_campaign(cfg(), ROBOT)
        for i in range(4):
            _measure(store, cid, i)
        own_postgres.stop()
        began = time.monotonic()
        with pytest.raises(StoreError) as raised:
            _measure(store, cid, 4)
        assert 0.9 < time.monotonic() - began < 15
        assert type(raised.value) is StoreUnavailable and isinstance(raised.value, FaultError)
        text = str(raised.value)
        assert "cannot record the measurement of pose 4" in text and "did not come back within 1 s" in text
        assert "\n" not in text
        assert len(told) == 1 and told[0] is not None  # gone, and never said back
        own_postgres.start()
        _check_measured(store, cid, 4)  # everything recorded before
        _measure(store, cid, 4)  # and the store carries on
        _check_measured(store, cid, 5)
    finally:
        store.close()
    with Store.open(url) as again:
        _check_measured(again, cid, 5)


def test_a_write_whose_commit_landed_but_whose_answer_was_lost_is_not_repeated(pg_url, monkeypatch):
    """The link drops right after the server committed: the store cannot tell, retries, and finds its
    own rows (measurement by campaign, pose and t; event by uid; campaign by id; lease by token;
    model and validation by content) instead of writing them twice."""
    with Store.open(pg_url) as store:
        told: list[str | None] = []
        store.on_outage = told.append
        dialect = store._get_engine().dialect
        real_commit = dialect.do_commit
        armed: list[bool] = []

        def commit_then_lose_the_link(dbapi_connection: Any) -> None:
            real_commit(dbapi_connection)
            if armed:
                armed.pop()
                raise psycopg.OperationalError("server closed the connection unexpectedly")

        monkeypatch.setattr(dialect, "do_commit", commit_then_lose_the_link)

        def once(write: Any) -> Any:
            armed.append(True)
            result = write()
            assert not armed  # the fault did fire
            return result

        cid = once(lambda: store.create_campaign(cfg(), ROBOT))
        lease = once(lambda: store.claim_new(cfg("cell-2"), RobotIdentity("ur5e", "2023550077"),
                                             heartbeat=False))
        once(lambda: store.save_plan(cid, plan(2, 0)))
        mid = once(lambda: _measure(store, cid, 0))
        measured = PointMeasured(campaign=cid, t=T0 + 1, index=1, role="calibration", q=[0.1] * 6,
                                 p=[1, 2, 3], p_spread=[0] * 3, samples=1)
        seq = once(lambda: store.record_event(measured))
        model = once(lambda: store.save_model(cid, model_doc()))
        once(lambda: store.save_validation(cid, {"rms": 1e-3}, {"rms": 2e-5}, True))
        once(lambda: store.set_status(cid, "running"))
        assert told == ["database link lost (server closed the connection unexpectedly); waiting up to 600 s "
                        "for it to come back", None] * 8
        assert [c.id for c in store.campaigns(station="cell-1")] == [cid]
        assert count(store, "SELECT count(*) FROM campaigns") == 2
        assert {r["name"] for r in store.leases()} == {f"campaign:{lease.campaign}", "robot:2023550077"}
        assert [m.id for m in store.measurements(cid)] == [mid, store.measured_poses(cid)[1].id]
        assert len(store.samples(mid)["tracker"]) == 2
        assert seq == 1 and [s for s, _ in store.event_log(cid)] == [1]
        assert [m.id for m in store.campaign(cid).models] == [model]
        assert count(store, "SELECT count(*) FROM validations") == 1
        assert [p.status for p in store.poses(cid)] == ["measured", "measured"]
        lease.release()
        assert store.leases() == []


def test_a_crashed_server_keeps_every_committed_measurement(own_postgres):
    url = own_postgres.create_database("crash")
    with Store.open(url) as store:
        told: list[str | None] = []
        store.on_outage = told.append
        cid = store.create_campaign(cfg(), ROBOT)
        committed: list[int] = []
        stop = threading.Event()
        failures: list[BaseException] = []

        def writer() -> None:
            try:
                i = 0
                while not stop.is_set():
                    _measure(store, cid, i)
                    committed.append(i)  # record_measurement returned: committed
                    i += 1
            except BaseException as exc:
                failures.append(exc)

        thread = threading.Thread(target=writer, daemon=True)
        thread.start()
        deadline = time.monotonic() + 30
        while len(committed) < 20:
            assert time.monotonic() < deadline and not failures, failures
            time.sleep(0.01)
        own_postgres.kill()  # mid-write, as like as not
        at_crash = len(committed)
        time.sleep(0.5)
        own_postgres.start()
        while len(committed) < at_crash + 10:
            assert time.monotonic() < deadline + 30 and not failures, failures
            time.sleep(0.01)
        stop.set()
        thread.join(timeout=30)
        assert not thread.is_alive() and failures == []
        assert told[0] is not None and told[-1] is None  # the writer waited for the server
        _check_measured(store, cid, len(committed))
    with Store.open(url) as again:
        _check_measured(again, cid, len(committed))


# --- 11. SQLite stores from before Alembic ------------------------------------------------------------
LEGACY_ID = "20231114-221320-0abc"


def _legacy_store(path: Path, version: int) -> dict[str, Any]:
    """A store as hil wrote it at schema `version` (1 to 3), one unfinished campaign in it, put there
    with plain SQL matching that version's tables."""
    make_legacy(path, version)
    config = cfg("old-cell")
    tracker = [[1.0, 2.0, 3.0 + 1 / 3], [1.0, 2.0 + 1e-9, 3.0], [5e-324, -0.0, 1 / 7]]
    doc = model_doc()
    conn = sqlite3.connect(path, isolation_level=None)
    try:
        conn.execute("BEGIN")
        conn.execute("INSERT INTO stations (id, name, created) VALUES (1, 'old-cell', ?)", (T0,))
        conn.execute("INSERT INTO robots (id, serial, type, model, software, first_seen, last_seen) "
                     "VALUES (1, ?, 'ur5e', 'UR5e', '5.15.0', ?, ?)", (ROBOT.serial, T0, T0))
        columns = ["id", "station", "robot", "robot_type", "config", "plan", "status", "detail", "software",
                   "created", "updated"]
        values: list[Any] = [LEGACY_ID, 1, 1, "ur5e", json.dumps(config), json.dumps({"method": "tabu"}),
                             "running", "", "0.9", T0, T0 + 50]
        if version >= 2:  # what that hil wrote with each campaign
            columns.append("config_hash")
            values.append(config_hash(config))
        if version >= 3:
            columns.append("measure_hash")
            values.append(measurement_hash(config))
        conn.execute(f"INSERT INTO campaigns ({', '.join(columns)}) VALUES ({', '.join('?' * len(values))})",
                     values)
        poses = ((0, "calibration", "measured", ""), (1, "calibration", "measured", ""),
                 (2, "calibration", "skipped", "no line of sight"), (3, "calibration", "planned", ""),
                 (4, "validation", "planned", ""))
        for idx, role, status, reason in poses:
            conn.execute("INSERT INTO poses (campaign, idx, role, target, status, reason) "
                         "VALUES (?, ?, ?, ?, ?, ?)",
                         (LEGACY_ID, idx, role, json.dumps([idx / 10] * 6), status, reason))
        for mid, pose, p, t in ((1, 0, [1.0, 2.0, 3.0], T0 + 10), (2, 1, [1.0, 2.0, 4.0], T0 + 20),
                                (3, 1, [1.0, 2.0, 4.5], T0 + 30)):
            q = list(AWKWARD_Q) if pose == 0 else [pose / 10] * 6
            conn.execute("INSERT INTO measurements (id, campaign, pose, role, q, q_spread, p, p_spread, "
                         "samples, deviation, t) VALUES (?, ?, ?, 'calibration', ?, NULL, ?, ?, 3, ?, ?)",
                         (mid, LEGACY_ID, pose, json.dumps(q), json.dumps(p), json.dumps([1e-6] * 3),
                          1e-4 * mid, t))
        for k, v in enumerate(tracker):
            conn.execute("INSERT INTO samples (measurement, kind, k, value) VALUES (1, 'tracker', ?, ?)",
                         (k, json.dumps(v)))
        conn.execute("INSERT INTO models (id, campaign, doc, sha256, rms, created) "
                     "VALUES (1, ?, ?, 'abc', ?, ?)", (LEGACY_ID, json.dumps(doc), 20e-6, T0 + 40))
        conn.execute("INSERT INTO validations (id, campaign, model, before, after, passed, rms, details, "
                     "sha256, created) VALUES (1, ?, 1, ?, ?, 0, ?, NULL, 'def', ?)",
                     (LEGACY_ID, json.dumps({"rms": 1e-3}), json.dumps({"rms": 3e-4}), 3e-4, T0 + 45))
        events = [RunStarted(campaign=LEGACY_ID, t=T0 + 1, robot="ur5e", station="old-cell", poses=5),
                  PoseStarted(campaign=LEGACY_ID, t=T0 + 5, index=0, role="calibration", target=[0.0] * 6),
                  PoseSkipped(campaign=LEGACY_ID, t=T0 + 25, index=2, role="calibration",
                              reason="no line of sight"),
                  ValidationDone(campaign=LEGACY_ID, t=T0 + 45, before={"rms": 1e-3}, after={"rms": 3e-4},
                                 passed=False)]
        for seq, ev in enumerate(events, 1):  # an older hil's RunStarted: no owner
            conn.execute("INSERT INTO events (campaign, seq, t, type, data) VALUES (?, ?, ?, ?, ?)",
                         (LEGACY_ID, seq, ev.t, ev.name, json.dumps(ev.to_dict())))
        if version >= 3:  # a lease left by a run that died
            done = subprocess.Popen(["true"])
            done.wait(timeout=10)
            owner = {"host": socket.gethostname(), "pid": done.pid, "boot": "", "started": None}
            conn.execute("INSERT INTO leases (name, campaign, owner, token, since, heartbeat) "
                         "VALUES (?, ?, ?, 'old-token', ?, ?)",
                         (f"campaign:{LEGACY_ID}", LEGACY_ID, json.dumps(owner), T0, T0))
        conn.execute("COMMIT")
    finally:
        conn.close()
    return {"config": config, "tracker": tracker, "doc": doc, "events": events}


@pytest.mark.parametrize("version", [1, 2, 3])
def test_an_sqlite_store_from_before_alembic_upgrades_in_place(tmp_path, version, upgrades, monkeypatch):
    path = tmp_path / "old.db"
    old = _legacy_store(path, version)
    with Store.open(path) as s:
        assert upgrades == ["0006"]
        assert raw(s).execute("SELECT version_num FROM alembic_version").fetchall() == [("0006",)]
        assert count(s, "PRAGMA user_version") == SCHEMA_VERSION == 6
        rec = s.campaign(LEGACY_ID)
        assert rec.config == old["config"] and rec.config_hash == config_hash(old["config"])
        assert rec.robot == ROBOT and rec.plan == {"method": "tabu"} and rec.software == "0.9"
        summary = rec.summary
        assert (summary.station, summary.status, summary.planned, summary.measured, summary.skipped) == (
            "old-cell", "running", 5, 2, 1)  # an owner-less run: nothing says it died
        assert [p.index for p in s.pending_poses(LEGACY_ID)] == [3, 4]
        assert [m.id for m in s.measurements(LEGACY_ID)] == [1, 2, 3]
        latest = s.measured_poses(LEGACY_ID)
        assert list(latest) == [0, 1] and latest[1].id == 3 and latest[1].p == (1.0, 2.0, 4.5)
        assert bits(latest[0].q) == bits(AWKWARD_Q) and bits(latest[0].deviation) == bits(1e-4)
        assert bits(s.samples(1)["tracker"]) == bits(old["tracker"])
        assert s.model(LEGACY_ID) == old["doc"] and rec.model is not None and rec.model.rms == 20e-6
        assert rec.validation is not None and rec.validation.model == 1 and rec.validation.passed is False
        assert s.events(LEGACY_ID) == old["events"]
        # resume finds it: by serial, and by address with a changed tracker URL (the backfilled hashes)
        assert s.find_resumable(old["config"], ROBOT.serial) == LEGACY_ID
        assert s.find_resumable(cfg("old-cell", tracker__url="tcp://elsewhere:1")) == LEGACY_ID
        # and it runs on: the log continues, with the new column; a dead run's lease is taken over
        with s.claim(LEGACY_ID, ROBOT.serial, heartbeat=False):
            assert s.record_event(RunStarted(campaign=LEGACY_ID, robot="ur5e", station="old-cell", poses=5,
                                             resumed=True, measured=2)) == 5
            _measure(s, LEGACY_ID, 3)
        assert count(s, "SELECT count(*) FROM events WHERE uid IS NOT NULL") == 1
        assert s.leases() == []
    stamps: list[str] = []
    monkeypatch.setattr(alembic_command, "stamp", lambda cfg, rev, *a, **k: stamps.append(rev))
    with Store.open(path) as s:  # a second open: nothing to upgrade
        assert s.find_resumable(old["config"], ROBOT.serial) == LEGACY_ID
        assert sorted(s.measured_poses(LEGACY_ID)) == [0, 1, 3]
    assert upgrades == ["0006"] and stamps == []


def test_a_database_that_does_not_exist_is_bad_input_and_a_server_that_does_not_answer_a_fault(pg_url):
    """A typo in the URL's database name is the user's to fix (exit 2); a server down is the station's
    (exit 3). Neither creates anything."""
    from hil.errors import FaultError
    from hil.store.sqlite_errors import StoreUnavailable

    missing = pg_url.rsplit("/", 1)[0] + "/no_such_database"
    with pytest.raises(InputError, match="no_such_database"):
        Store.open(missing)
    nobody = "postgresql://hil@127.0.0.1:9/hil"  # the discard port: nothing listens
    with pytest.raises(StoreUnavailable) as down:
        Store(nobody, timeout=2.0).connect()
    assert isinstance(down.value, FaultError) and "cannot open" in str(down.value)
