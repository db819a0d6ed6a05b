"""The durable store: schema and upgrades, recording and reading back, resume queries, durability
across kill -9, and a reader running while the engine writes."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
from alembic import command as alembic_command
from sqlalchemy import event

from hil.campaign.events import (
    EventBus,
    Message,
    ModelIdentified,
    PhaseChanged,
    PointMeasured,
    PoseReached,
    PoseSkipped,
    PoseStarted,
    Resumed,
    RunFinished,
    RunStarted,
    StateChanged,
    Suspended,
    ValidationDone,
)
from hil.errors import InputError
from hil.station.config import default_config, load_config
from hil.store import (
    SCHEMA_VERSION,
    PlannedPose,
    RobotIdentity,
    Store,
    StoreError,
    UnknownCampaignError,
    config_hash,
    default_path,
    resolve_location,
    resolve_path,
    simulated_path,
)
from tests.hil.store.legacy_schema import make_legacy
from tests.hil.store.raw import Raw, raw

ROOT = Path(__file__).resolve().parents[3]
ROBOT = RobotIdentity(type="ur5e", serial="20235500123", model="UR5e", software="5.15.0")


def cfg(name: str = "cell-1", **overrides):
    config = default_config()
    data = config.as_dict()
    data["station"]["name"] = name
    for dotted, value in overrides.items():
        section, key = dotted.split("__")
        data[section][key] = value
    return data


def plan(n_cal: int = 4, n_val: int = 2):
    rows = [(i, "calibration", [0.1 * i, -1.0, 1.0, 0.0, 0.5, 0.0]) for i in range(n_cal)]
    rows += [(n_cal + i, "validation", [0.2 * i, -1.2, 1.1, 0.1, 0.5, 0.0]) for i in range(n_val)]
    return rows


@pytest.fixture
def db(tmp_path) -> Path:
    return tmp_path / "data" / "hil.db"


@pytest.fixture
def store(db):
    with Store.open(db) as s:
        yield s


# --- schema -------------------------------------------------------------------------------------
def test_constructor_does_no_io(db):
    s = Store(db)
    assert not db.exists() and not db.parent.exists()
    with s:
        assert db.exists()


def test_fresh_database_schema_and_pragmas(store, db):
    with store.reading() as c:  # the store's own connection: pragmas are per connection
        conn = Raw(c)
        assert conn.execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION
        assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        assert conn.execute("PRAGMA foreign_keys").fetchone()[0] == 1
        assert conn.execute("PRAGMA synchronous").fetchone()[0] == 2  # FULL
        assert conn.execute("PRAGMA busy_timeout").fetchone()[0] == 10000
        tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    assert {"stations", "robots", "campaigns", "poses", "measurements", "samples", "models",
            "validations", "events"} <= tables
    # a second, independent opener sees WAL too (it is persistent in the file)
    raw = sqlite3.connect(db)
    assert raw.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    raw.close()


def _v1_database(path: Path) -> str:
    """A database as version 1 of the code wrote it, with one unfinished campaign."""
    path.parent.mkdir(parents=True, exist_ok=True)
    make_legacy(path, 1)
    conn = sqlite3.connect(path, isolation_level=None)
    assert conn.execute("PRAGMA user_version").fetchone()[0] == 1
    conn.execute("INSERT INTO stations (id, name, created) VALUES (1, 'old', 0)")
    conn.execute("INSERT INTO campaigns (id, station, robot_type, config, status, created, updated) "
                 "VALUES ('20240101-000000-abcd', 1, 'ur5e', ?, 'running', 1, 1)",
                 (json.dumps(cfg("old")),))
    conn.close()
    return "20240101-000000-abcd"


def test_upgrade_from_v1(db):
    cid = _v1_database(db)
    with Store.open(db) as s:
        conn = raw(s)
        assert conn.execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION == 6
        assert conn.execute("SELECT version_num FROM alembic_version").fetchone()[0] == "0006"
        assert s.find_resumable(cfg("old")) == cid  # the backfilled config and measurement hashes
        assert s.campaign(cid).config_hash == config_hash(cfg("old"))
        indexes = {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'index'")}
        assert {"campaigns_resume", "events_type"} <= indexes


def test_failed_upgrade_leaves_the_old_version(db, monkeypatch):
    _v1_database(db)

    real = alembic_command.upgrade

    def broken(cfg, revision):
        real(cfg, "0002")  # the next revision ran...
        raise RuntimeError("upgrade failed half-way")  # ...and then something failed

    monkeypatch.setattr(alembic_command, "upgrade", broken)
    with pytest.raises(RuntimeError):
        Store.open(db)
    conn = sqlite3.connect(db)
    assert conn.execute("PRAGMA user_version").fetchone()[0] == 1
    columns = {r[1] for r in conn.execute("PRAGMA table_info(campaigns)")}
    assert "config_hash" not in columns
    conn.close()


def test_newer_database_is_refused(db):
    Store.open(db).close()
    conn = sqlite3.connect(db)
    conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 1}")
    conn.close()
    with pytest.raises(InputError, match="newer than this hil supports"):
        Store.open(db)


def test_bad_files_are_input_errors(tmp_path):
    with pytest.raises(InputError, match="no such database"):
        Store.open(tmp_path / "missing.db", create=False)
    assert not (tmp_path / "missing.db").exists()
    junk = tmp_path / "junk.db"
    junk.write_bytes(b"this is not an SQLite file at all " * 200)
    with pytest.raises(InputError, match="not a hil database"):
        Store.open(junk)
    other = tmp_path / "other.db"
    conn = sqlite3.connect(other)
    conn.execute("CREATE TABLE t (x)")
    conn.close()
    with pytest.raises(InputError, match="not a hil store"):
        Store.open(other)
    with pytest.raises(InputError, match="directory"):
        Store.open(tmp_path)


def test_closed_store_refuses(db):
    s = Store.open(db)
    s.close()
    with pytest.raises(StoreError, match="closed"):
        s.campaigns()


# --- where the file lives -----------------------------------------------------------------------
def test_paths(tmp_path, monkeypatch):
    home = Path.home()
    assert default_path({}) == home / ".local" / "share" / "hil" / "hil.db"
    assert default_path({"XDG_DATA_HOME": "/x/data"}) == Path("/x/data/hil/hil.db")
    assert default_path({"XDG_DATA_HOME": "relative"}) == home / ".local/share/hil/hil.db"
    station = tmp_path / "station.toml"
    station.write_text('[store]\npath = "results/cell.db"\n')
    config = load_config(station)
    assert resolve_path(None, config, {}) == tmp_path / "results" / "cell.db"
    assert resolve_path(None, config, {"HIL_DB": "/env.db"}) == Path("/env.db")
    assert resolve_path("/flag.db", config, {"HIL_DB": "/env.db"}) == Path("/flag.db")
    assert resolve_path(None, default_config(), {"XDG_DATA_HOME": "/d"}) == Path("/d/hil/hil.db")
    monkeypatch.setenv("HIL_DB", str(tmp_path / "env.db"))
    with Store.open() as s:
        assert s.path == tmp_path / "env.db"


def test_a_simulated_stations_store_is_its_own_whatever_hil_db_says():
    """--sim: the simulated stations' store beside the default, never $HIL_DB's (the plant's history);
    --db names any store, that one included."""
    env = {"XDG_DATA_HOME": "/d", "HIL_DB": "postgresql://hil@plant/hil"}
    assert resolve_location(None, None, env, simulated=True) == Path("/d/hil/sim.db") == simulated_path(env)
    assert resolve_location(None, None, env) == "postgresql://hil@plant/hil"
    assert resolve_location("/mine.db", None, env, simulated=True) == Path("/mine.db")
    assert resolve_location("postgresql://hil@plant/hil", None, env, simulated=True) == env["HIL_DB"]


# --- recording and reading back -----------------------------------------------------------------
def test_campaign_record_and_reload(db):
    with Store.open(db) as s:
        cid = s.create_campaign(cfg(), ROBOT, {"method": "tabu", "index": "O1", "value": 1.5})
        s.save_plan(cid, plan())
        rng = np.random.default_rng(1)
        tracker = rng.normal(size=(5, 3))
        joints = rng.normal(size=(10, 6))
        mid = s.record_measurement(cid, 0, "calibration", np.arange(6) * 0.1, tracker.mean(axis=0),
                                   q_spread=[1e-6] * 6, p_spread=[2e-6] * 3, samples=5,
                                   deviation=1e-3, t=100.0, tracker_samples=tracker,
                                   joint_samples=joints)
    with Store.open(db, create=False) as s:
        rec = s.campaign(cid)
        assert rec.summary.station == "cell-1" and rec.summary.robot == "ur5e"
        assert rec.robot == ROBOT
        assert rec.config == cfg() and rec.plan["method"] == "tabu"
        assert rec.summary.status == "created"
        assert (rec.summary.planned, rec.summary.measured) == (6, 1)
        m = s.measured_poses(cid)[0]
        assert m.id == mid and m.q == tuple(np.arange(6) * 0.1) and m.p == tuple(tracker.mean(axis=0))
        assert m.q_spread == (1e-6,) * 6 and m.samples == 5 and m.deviation == 1e-3 and m.t == 100.0
        raw = s.samples(mid)
        np.testing.assert_array_equal(np.array(raw["tracker"]), tracker)  # bit-exact round trip
        np.testing.assert_array_equal(np.array(raw["joints"]), joints)
        q, p = s.arrays(cid, "calibration")
        assert q.shape == (1, 6) and p.shape == (1, 3)
        assert s.arrays(cid, "validation")[0].shape == (0, 6)


def test_robot_rows_are_shared_by_serial(store):
    a = store.create_campaign(cfg(), ROBOT)
    b = store.create_campaign(cfg(), RobotIdentity("ur5e", ROBOT.serial, "UR5e", "5.16.0"))
    c = store.create_campaign(cfg(), {"type": "ur10e", "extra": "ignored"})
    d = store.create_campaign(cfg())  # robot type from the config, serial unknown
    conn = raw(store)
    assert conn.execute("SELECT count(*) FROM robots").fetchone()[0] == 1
    assert store.campaign(a).robot.software == "5.16.0"  # the robot row follows its controller
    assert store.campaign(b).robot.serial == ROBOT.serial
    assert store.campaign(c).robot == RobotIdentity("ur10e")
    assert store.campaign(d).robot.type == "ur5e"
    assert len({a, b, c, d}) == 4


def test_save_plan_replaces_planned_but_not_measured(store):
    cid = store.create_campaign(cfg(), ROBOT)
    store.save_plan(cid, [(0, "bootstrap", [0] * 6), (1, "bootstrap", [0.1] * 6)])
    store.record_measurement(cid, 0, "bootstrap", [0] * 6, [1, 1, 1], t=1.0)
    store.save_plan(cid, [PlannedPose(1, "calibration", (0.2,) * 6), (2, "validation", [0.3] * 6)],
                    plan={"method": "exchange"})
    store.save_plan(cid, [(0, "bootstrap", [0] * 6)])  # unchanged measured pose: fine
    assert [(p.index, p.role, p.target[0], p.status) for p in store.poses(cid)] == [
        (0, "bootstrap", 0.0, "measured"), (1, "calibration", 0.2, "planned"),
        (2, "validation", 0.3, "planned")]
    assert store.campaign(cid).plan == {"method": "exchange"}
    with pytest.raises(StoreError, match="already measured"):
        store.save_plan(cid, [(0, "bootstrap", [0.5] * 6)])
    with pytest.raises(StoreError, match="role"):
        store.save_plan(cid, [(3, "warmup", [0] * 6)])
    with pytest.raises(StoreError, match="6 numbers"):
        store.save_plan(cid, [(3, "calibration", [0] * 5)])


def test_unknown_campaign_is_a_store_error(store):
    with pytest.raises(StoreError, match="no campaign"):
        store.record_measurement("nope", 0, "calibration", [0] * 6, [0] * 3)
    with pytest.raises(StoreError, match="no campaign"):
        store.record_event(Message(campaign="nope", level="info", text="hi"))
    with pytest.raises(StoreError, match="no campaign"):
        store.set_status("nope", "running")
    with pytest.raises(UnknownCampaignError):
        store.campaign("nope")


def _model_doc(rms=20e-6):
    return {"format": "hil-model/1", "robot": "ur5e", "fit": {"rms": rms, "max": 3 * rms},
            "parameters": [{"name": "a", "value": 0.0, "std": 1e-6}]}


def test_events_drive_the_derived_state(store):
    cid = store.create_campaign(cfg(), ROBOT)
    store.save_plan(cid, plan(2, 1))
    bus = EventBus()
    bus.subscribe(store.as_subscriber(), critical=True)
    events = [
        RunStarted(campaign=cid, robot="ur5e", station="cell-1", poses=3),
        StateChanged(campaign=cid, state="running", previous="idle"),
        PhaseChanged(campaign=cid, phase="measure"),
        PoseStarted(campaign=cid, index=0, role="calibration", target=[0] * 6),
        PoseReached(campaign=cid, index=0, role="calibration", q=[0] * 6, q_spread=[3e-6] * 6,
                    seconds=2.0),
        PointMeasured(campaign=cid, index=0, role="calibration", q=[0] * 6, p=[1, 2, 3],
                      p_spread=[1e-6] * 3, samples=5, deviation=float("nan")),
        Suspended(campaign=cid, kind="beam_lost", message="re-lock the beam"),
    ]
    for ev in events:
        bus.emit(ev)
    assert store.campaign(cid).summary.status == "running"  # suspended is a StateChanged, not this
    bus.emit(StateChanged(campaign=cid, state="suspended", previous="running"))
    assert store.campaigns()[0].status == "suspended"
    more = [
        Resumed(campaign=cid, kind="beam_lost", waited=3.0),
        PoseSkipped(campaign=cid, index=1, role="calibration", reason="no line of sight"),
        PoseStarted(campaign=cid, index=7, role="validation", target=[0.7] * 6),  # not in the plan
        PointMeasured(campaign=cid, index=7, role="validation", q=[0.7] * 6, p=[1, 2, 4],
                      p_spread=[1e-6] * 3, samples=5),
        ModelIdentified(campaign=cid, rms=20e-6, max=60e-6, iterations=5, rejected=[],
                        model=_model_doc()),
        ValidationDone(campaign=cid, before={"count": 1, "rms": 1.8e-3, "max": 2e-3, "mean": 1e-3},
                       after={"count": 1, "rms": 21e-6, "max": 30e-6, "mean": 20e-6}, passed=True),
        RunFinished(campaign=cid, status="accepted", detail="0.021 mm", result={"passed": True}),
    ]
    for ev in more:
        bus.emit(ev)
    rec = store.campaign(cid)
    s = rec.summary
    assert (s.status, s.planned, s.measured, s.skipped) == ("accepted", 4, 2, 1)
    assert s.fit_rms == 20e-6 and s.validation_rms == 21e-6 and s.passed is True and s.finished
    assert rec.detail == "0.021 mm" and rec.result == {"passed": True}
    m0 = store.measured_poses(cid)[0]
    assert m0.q_spread == (3e-6,) * 6 and m0.deviation is None  # spread from PoseReached; NaN → None
    assert [p.index for p in store.pending_poses(cid)] == [2]
    assert [p.index for p in store.pending_poses(cid, include_skipped=True)] == [1, 2]
    assert rec.model is not None and rec.model.doc == _model_doc() and rec.model.rms == 20e-6
    assert rec.validation is not None and rec.validation.model == rec.model.id
    assert rec.event_counts["PointMeasured"] == 2 and rec.event_counts["RunStarted"] == 1
    # the log reads back as the same events, in order, with increasing sequence numbers
    log = store.event_log(cid)
    assert [seq for seq, _ in log] == list(range(1, len(events) + len(more) + 2))
    back = store.events(cid)
    assert [e.name for e in back] == [e["event"] for _, e in log]
    assert back[0] == events[0] and back[-1] == more[-1]
    assert [e.name for e in store.events(cid, after=len(log) - 2)] == ["ValidationDone", "RunFinished"]


def test_direct_calls_and_events_do_not_duplicate(store):
    cid = store.create_campaign(cfg(), ROBOT)
    mid = store.record_measurement(cid, 3, "calibration", [0.3] * 6, [1, 2, 3], q_spread=[1e-6] * 6,
                                   samples=2, t=42.0, tracker_samples=[[1, 2, 3], [1, 2, 3]])
    store.record_event(PointMeasured(campaign=cid, t=42.0, index=3, role="calibration", q=[0.3] * 6,
                                     p=[1, 2, 3], p_spread=[0] * 3, samples=2))
    assert [m.id for m in store.measurements(cid)] == [mid]
    assert store.measured_poses(cid)[3].q_spread == (1e-6,) * 6
    assert len(store.samples(mid)["tracker"]) == 2
    doc = _model_doc()
    model_id = store.save_model(cid, doc)
    store.record_event(ModelIdentified(campaign=cid, rms=1, max=1, iterations=1, rejected=[],
                                       model=doc))
    assert store.save_model(cid, doc) == model_id and len(store.campaign(cid).models) == 1
    v = store.save_validation(cid, {"rms": 1e-3}, {"rms": 2e-5}, True, details={"AP": 1e-5})
    assert store.save_validation(cid, {"rms": 1e-3}, {"rms": 2e-5}, True, details={"AP": 1e-5}) == v
    # a re-measurement of the same pose is a new row; readers take the latest
    store.record_measurement(cid, 3, "calibration", [0.3] * 6, [1, 2, 3.5], t=43.0)
    assert len(store.measurements(cid)) == 2 and store.measured_poses(cid)[3].p[2] == 3.5


def test_critical_subscriber_failure_stops_the_run(store):
    bus = EventBus()
    bus.subscribe(store.as_subscriber(), critical=True)
    with pytest.raises(StoreError):
        bus.emit(RunStarted(campaign="never-created", robot="ur5e", station="x", poses=1))


# --- resume -------------------------------------------------------------------------------------
def test_resume_queries(store):
    config = cfg()
    assert store.find_resumable(config) is None
    done = store.create_campaign(config, ROBOT, now=1000.0)
    store.set_status(done, "accepted")
    killed = store.create_campaign(config, ROBOT, now=2000.0)
    store.save_plan(killed, plan(4, 2))
    for i in (0, 1, 3):
        store.record_measurement(killed, i, "calibration", [0.1 * i] * 6, [0, 0, i], t=2000.0 + i)
    store.set_status(killed, "running")
    other = store.create_campaign(cfg("cell-2"), ROBOT, now=3000.0)
    assert store.find_resumable(config) == killed
    assert store.find_resumable(config, ROBOT.serial) == killed
    assert store.find_resumable(config, "another-arm") is None  # never resume another robot's run
    assert store.find_resumable(cfg("cell-2")) == other
    assert store.find_resumable(config_sha256=config_hash(config)) == killed
    # where the database lives does not change the campaign
    assert store.find_resumable(cfg(store__path="/elsewhere.db")) == killed
    assert store.find_resumable(cfg(campaign__samples=9)) is None
    assert sorted(store.measured_poses(killed)) == [0, 1, 3]
    assert [p.index for p in store.pending_poses(killed)] == [2, 4, 5]
    store.set_status(killed, "failed", "connection lost")  # a hardware fault: still resumable
    assert store.find_resumable(config) == killed
    store.set_status(killed, "aborted")
    assert store.find_resumable(config) is None


def test_campaign_listing_and_id_resolution(store):
    ids = [store.create_campaign(cfg("a" if i % 2 else "b"), ROBOT, now=1000.0 + i) for i in range(5)]
    assert [c.id for c in store.campaigns()] == ids[::-1]
    assert [c.id for c in store.campaigns(2)] == ids[:-3:-1]
    assert {c.station for c in store.campaigns(station="a")} == {"a"}
    assert store.resolve_id("last") == ids[-1]
    assert store.resolve_id(ids[2]) == ids[2]
    assert store.resolve_id(ids[2][:15]) == ids[2]  # date and time: unique here
    with pytest.raises(UnknownCampaignError, match="several"):
        store.resolve_id(ids[0][:8])
    with pytest.raises(UnknownCampaignError, match="no campaign"):
        store.resolve_id("1999")
    with pytest.raises(UnknownCampaignError, match="no campaign"):
        store.resolve_id("%")


# --- durability ---------------------------------------------------------------------------------
CHILD = r"""
import os, signal, sys
from hil.store import Store
db, stop_after = sys.argv[1], int(sys.argv[2])
store = Store.open(db)
cid = store.create_campaign({"station": {"name": "kill"}, "robot": {"type": "ur5e"}}, "ur5e")
print("campaign", cid, flush=True)
i = 0
while True:
    store.record_measurement(cid, i, "calibration", [i * 1e-3] * 6, [1.0, 2.0, float(i)], samples=3,
                             tracker_samples=[[1.0, 2.0, float(i)]] * 3)
    i += 1
    print("committed", i, flush=True)
    if i == stop_after:
        os.kill(os.getpid(), signal.SIGKILL)
"""


def _child(db: Path, stop_after: int) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", CHILD, str(db), str(stop_after)], cwd=ROOT,
                            stdout=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONPATH": str(ROOT)})


def _check_after_kill(db: Path, cid: str, at_least: int) -> int:
    with Store.open(db, create=False) as s:
        assert raw(s).execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        measured = s.measured_poses(cid)
        n = len(measured)
        assert n >= at_least
        assert sorted(measured) == list(range(n))  # nothing lost in the middle either
        for i, m in measured.items():
            assert m.p == (1.0, 2.0, float(i)) and len(s.samples(m.id)["tracker"]) == 3
        assert s.campaign(cid).summary.measured == n
    return n


def test_kill_9_right_after_commit_loses_nothing(tmp_path):
    db = tmp_path / "k.db"
    proc = _child(db, 25)
    out, _ = proc.communicate(timeout=30)
    assert proc.returncode == -signal.SIGKILL
    lines = out.splitlines()
    cid = lines[0].split()[1]
    assert lines[-1] == "committed 25"
    assert _check_after_kill(db, cid, 25) == 25


def test_kill_9_from_outside_mid_write_loses_nothing_acknowledged(tmp_path):
    db = tmp_path / "k.db"
    proc = _child(db, -1)  # records until killed
    assert proc.stdout is not None
    cid = proc.stdout.readline().split()[1]
    seen = 0
    while seen < 30:
        seen = int(proc.stdout.readline().split()[1])
    proc.kill()  # SIGKILL while it keeps writing
    proc.wait(timeout=10)
    proc.stdout.close()
    assert proc.returncode == -signal.SIGKILL
    _check_after_kill(db, cid, seen)


# --- runs whose process died ----------------------------------------------------------------------
RUNNER = r"""
import sys, time
from hil.campaign.events import RunStarted
from hil.store import Store
from hil.store import migrate as migrate_mod
from tests.hil.store.legacy_schema import make_legacy
from tests.hil.store.raw import Raw, raw, raw_write
store = Store.open(sys.argv[1])
store.record_event(RunStarted(campaign=sys.argv[2], robot="ur5e", station="cell-1", poses=6))
print("started", flush=True)
time.sleep(60)
"""


def test_a_run_whose_process_was_killed_reads_as_interrupted(store, db):
    """A campaign stays ``running`` in the file after kill -9; readers see its process is gone."""
    cid = store.create_campaign(cfg(), ROBOT)
    store.save_plan(cid, plan(4, 2))
    proc = subprocess.Popen([sys.executable, "-c", RUNNER, str(db), cid], cwd=ROOT, stdout=subprocess.PIPE,
                            text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    try:
        assert proc.stdout.readline() == "started\n"
        assert store.campaigns()[0].status == "running"  # alive: really running
        assert store.campaign(cid).summary.status == "running"
    finally:
        proc.kill()
        proc.wait(timeout=10)
        proc.stdout.close()
    (summary,) = store.campaigns()
    assert summary.status == "interrupted" and not summary.finished
    record = store.campaign(cid)
    assert record.summary.status == "interrupted" and "process ended" in record.detail
    assert store.find_resumable(cfg(), ROBOT.serial) == cid  # and resumable, as it was
    # a reader never writes: the file still says what the dead run left
    assert raw(store).execute("SELECT status FROM campaigns").fetchone()[0] == "running"
    # the next run (this process) owns it: running again
    store.record_event(RunStarted(campaign=cid, robot="ur5e", station="cell-1", poses=6, resumed=True))
    assert store.campaigns()[0].status == "running"


@pytest.mark.parametrize("sql", ["BEGIN IMMEDIATE", "BEGIN"])
def test_ctrl_c_just_after_begin_leaves_no_transaction_open(store, db, monkeypatch, sql):
    """The interrupted run records how it ended right after: a Ctrl-C landing just after BEGIN must
    not leave a transaction (and SQLite's lock) held by a pooled connection."""
    cid = store.create_campaign(cfg(), ROBOT)
    engine = store._get_engine()
    armed = [True]

    def interrupt(conn, cursor, statement, *args):
        if armed[0] and statement == sql:
            armed[0] = False
            raise KeyboardInterrupt

    event.listen(engine, "after_cursor_execute", interrupt)
    try:
        with pytest.raises(KeyboardInterrupt):
            if sql == "BEGIN":
                store.campaign(cid)
            else:
                store.set_status(cid, "running")
    finally:
        event.remove(engine, "after_cursor_execute", interrupt)
    other = sqlite3.connect(db, timeout=0, isolation_level=None)  # no lock left behind
    other.execute("BEGIN IMMEDIATE")
    other.execute("ROLLBACK")
    other.close()
    store.record_event(RunFinished(campaign=cid, status="interrupted"))
    assert store.campaign(cid).summary.status == "interrupted"


def test_run_owner_liveness():
    from hil.store import owner

    me = owner.this_process()
    assert not owner.is_gone(me)
    assert not owner.is_gone(None) and not owner.is_gone({})  # an older hil's run: cannot tell
    assert not owner.is_gone({**me, "host": "another-machine"})  # cannot tell either
    assert not owner.is_gone({**me, "pid": 0})  # never a process group
    done = subprocess.Popen(["true"])
    done.wait()
    assert owner.is_gone({**me, "pid": done.pid})
    if me["started"] is not None:  # Linux: a reused pid, and a zombie nobody reaped yet
        assert owner.is_gone({**me, "started": me["started"] - 1})
        zombie = subprocess.Popen(["true"])
        try:
            for _ in range(500):
                if owner._stat(zombie.pid)[0] == "Z":
                    break
                threading.Event().wait(0.01)
            assert owner.is_gone({**me, "pid": zombie.pid, "started": owner._stat(zombie.pid)[1]})
        finally:
            zombie.wait()
    if me["boot"]:  # the machine rebooted since (a power cut)
        assert owner.is_gone({**me, "boot": "another-boot"})


def test_run_started_by_an_older_hil_stays_running(store):
    """No owner in its RunStarted (recorded before owners were): nothing says it is dead."""
    cid = store.create_campaign(cfg(), ROBOT)
    store.record_event(RunStarted(campaign=cid, robot="ur5e", station="cell-1", poses=6))
    conn = raw(store)
    (data,) = conn.execute("SELECT data FROM events WHERE type = 'RunStarted'").fetchone()
    assert json.loads(data)["owner"]["pid"] == os.getpid()
    conn.execute("UPDATE events SET data = ? WHERE type = 'RunStarted'",
                 (json.dumps({k: v for k, v in json.loads(data).items() if k != "owner"}),))
    assert store.campaigns()[0].status == "running"


# --- threads --------------------------------------------------------------------------------------
def test_reader_runs_while_the_engine_writes(db):
    total = 150
    with Store.open(db) as s, Store.open(db) as other:  # `other` stands for another process
        cid = s.create_campaign(cfg(), ROBOT)
        s.save_plan(cid, [(i, "calibration", [0.01 * i] * 6) for i in range(total)])
        errors: list[BaseException] = []

        def engine() -> None:
            try:
                for i in range(total):
                    s.record_event(PointMeasured(campaign=cid, index=i, role="calibration",
                                                 q=[0.01 * i] * 6, p=[0, 0, i], p_spread=[0] * 3,
                                                 samples=1))
            except BaseException as exc:  # pragma: no cover - reported below
                errors.append(exc)

        worker = threading.Thread(target=engine)
        worker.start()
        seen, reads = [], 0
        while worker.is_alive() or reads == 0:
            reader = s if reads % 2 else other
            counts = (len(reader.measured_poses(cid)), reader.campaigns(1)[0].measured)
            seen.append(min(counts))
            reads += 1
        worker.join()
        assert not errors
        assert seen == sorted(seen)  # monotonic: every read saw a consistent, growing state
        assert reads >= 1
        assert s.campaign(cid).summary.measured == total == len(other.measured_poses(cid))
        pool = s._get_engine().pool
        assert pool.checkedout() == 0  # none held between transactions
        assert pool.checkedin() <= 2  # the worker's and ours, reused


def test_connections_of_ended_threads_are_closed(db):
    with Store.open(db) as s:
        for _ in range(3):
            t = threading.Thread(target=s.campaigns)
            t.start()
            t.join()
        s.campaigns()
        pool = s._get_engine().pool
        assert pool.checkedout() == 0 and pool.checkedin() <= 2


def test_store_url_in_the_config_names_a_file_or_a_server(tmp_path):
    from hil.store import resolve_location

    station = tmp_path / "station.toml"
    station.write_text('[store]\nurl = "postgresql://hil@db.plant.example:5432/hil"\n')
    assert resolve_location(None, load_config(station), {}) == "postgresql://hil@db.plant.example:5432/hil"
    assert resolve_location(None, load_config(station), {"HIL_DB": "/env.db"}) == Path("/env.db")
    station.write_text('[store]\nurl = "sqlite:///results/cell.db"\npath = "ignored.db"\n')
    assert resolve_location(None, load_config(station), {}) == tmp_path / "results" / "cell.db"
    assert resolve_location("postgresql://u@h/d", None, {}) == "postgresql://u@h/d"
    for bad, words in (("mysql://u@h/d", "postgresql:// URL"), ("postgresql:///d", "needs a host"),
                       ("sqlite://rel.db", "sqlite:///")):
        station.write_text(f'[store]\nurl = "{bad}"\n')
        with pytest.raises(InputError, match="store.url") as refused:
            load_config(station)
        assert words in str(refused.value)


def test_another_databases_url_is_bad_input_and_creates_nothing(tmp_path, monkeypatch, capsys):
    from hil.cli import main
    from hil.store import resolve_location

    monkeypatch.chdir(tmp_path)
    with pytest.raises(InputError, match=r"^--db: mysql:// is not a store"):
        resolve_location("mysql://u@h/d", None, {})
    with pytest.raises(InputError, match=r"^\$HIL_DB: mysql://"):
        resolve_location(None, None, {"HIL_DB": "mysql://u@h/d"})
    assert main(["history", "--db", "mysql://u@h/d"]) == 2
    assert capsys.readouterr().err.strip() == ("hil: error: --db: mysql:// is not a store; give a file "
                                               "path or a postgresql:// URL")
    assert list(tmp_path.iterdir()) == []
