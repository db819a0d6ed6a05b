"""A plant's fleet in the store (`hil.store.fleet`): the fleet listing, one robot's history with its
geometry changes beyond uncertainty, marks, and the current model falling back when one is marked bad.

Written against `fleet_store_location` (tests/hil/conftest.py), the realistic fleet of
`tests.hil.fleet_data`: three robots, three calibrations each at two stations, one hit between its
second and third calibration.
"""

from __future__ import annotations

import getpass
import json
import socket
import subprocess

import pytest
from sqlalchemy import event, func, insert, select

from hil.errors import InputError
from hil.store import Store, UnknownCampaignError
from hil.store import tables as tb
from hil.store.fleet import (
    DEFAULT_K,
    UnknownSerialError,
    calibrations,
    compare_parameters,
    current_model,
    fleet,
    geometry_changes,
    mark,
    robot_history,
)
from tests.hil.fleet_data import (
    ACCEPT,
    DAY,
    HIT,
    HIT_PARAMETER,
    HIT_ROBOT,
    REJECTING,
    ROBOTS,
    STATIONS,
    STEADY,
    T0,
    Fleet,
)


@pytest.fixture
def store(fleet_store_location):
    with Store.open(fleet_store_location) as s:
        yield s


def marks_in(store: Store) -> int:
    with store.reading() as conn:
        return conn.execute(select(func.count()).select_from(tb.marks)).scalar_one()


# --- the fleet ------------------------------------------------------------------------------------------
def test_the_fleet_lists_each_robot_its_last_calibration_and_current_model(store, built_fleet: Fleet):
    now = T0 + 100 * DAY
    rows = fleet(store, now=now)
    assert [r.serial for r in rows] == sorted(ROBOTS)  # by serial; the campaign without one is left out
    by = {r.serial: r for r in rows}
    for serial, ids in built_fleet.campaigns.items():
        r = by[serial]
        assert (r.type, r.calibrations, r.last) == (ROBOTS[serial], 3, ids[-1])
        assert r.station == built_fleet.stations[ids[-1]]
        assert r.age_days == pytest.approx((now - r.last_created) / DAY)
        assert r.before_rms > 1e-3 > ACCEPT  # the nominal arm: millimetres
        assert not r.marked_bad
    for serial in (STEADY, HIT_ROBOT):
        r = by[serial]
        assert (r.status, r.passed, r.current) == ("accepted", True, r.last)
        assert r.after_rms < ACCEPT and r.current_rms == r.after_rms
    r = by[REJECTING]  # its last calibration failed validation: the one before is current
    assert (r.status, r.passed) == ("rejected", False) and r.after_rms > ACCEPT
    assert r.current == built_fleet.campaigns[REJECTING][1] and r.current_rms < ACCEPT
    assert r.current_created < r.last_created
    doc = r.as_dict()
    assert doc["current"] == r.current and json.loads(json.dumps(doc)) == doc


def test_the_station_filter_keeps_robots_last_calibrated_there(store, built_fleet: Fleet):
    for station in STATIONS:
        rows = fleet(store, station=station)
        assert rows and all(r.station == station for r in rows)
        assert {r.serial for r in rows} == {s for s, ids in built_fleet.campaigns.items()
                                            if built_fleet.stations[ids[-1]] == station}
    with pytest.raises(InputError, match=r"no station named 'cell-9'.*eol-cell-1, eol-cell-2"):
        fleet(store, station="cell-9")


def test_a_run_whose_process_died_reads_as_interrupted(store):
    """As in `hil history`: 'running' in the store, but its process is gone (kill -9, power cut)."""
    gone = subprocess.Popen(["true"])
    gone.wait()
    cid = store.create_campaign({"station": {"name": STATIONS[0]}, "robot": {"type": "ur5e"}},
                                {"type": "ur5e", "serial": STEADY}, now=T0 + 90 * DAY)
    owner = {"host": socket.gethostname(), "pid": gone.pid, "boot": "", "started": None}
    with store.writing("record a run start") as conn:
        conn.execute(insert(tb.events).values(
            campaign=cid, seq=1, t=T0 + 90 * DAY, type="RunStarted",
            data=json.dumps({"event": "RunStarted", "campaign": cid, "owner": owner})))
    store.set_status(cid, "running")
    row = next(r for r in fleet(store, now=T0) if r.serial == STEADY)
    # in progress (resumable), not its last calibration: that is still its last finished one
    assert (row.in_progress, row.in_progress_status, row.calibrations) == (cid, "interrupted", 4)
    assert row.last == built_last(store) and row.status == "accepted"
    assert row.current != cid  # not accepted: the current model stays where it was


def built_last(store: Store) -> str:
    """STEADY's newest finished calibration."""
    return max((c for c in calibrations(store) if c.serial == STEADY and c.finished),
               key=lambda c: c.created).id


@pytest.mark.parametrize("status", ["interrupted", "failed", "running"])
def test_a_calibration_in_progress_is_not_the_robots_last_calibration(store, built_fleet: Fleet, status):
    """An interrupted campaign (or a failed one: resumable too, or one running now) is the robot's
    calibration in progress; its last calibration is its last finished one, with that one's result."""
    last_finished = built_fleet.campaigns[STEADY][-1]
    cid = store.create_campaign({"station": {"name": STATIONS[1]}, "robot": {"type": "ur5e"}},
                                {"type": "ur5e", "serial": STEADY}, now=T0 + 90 * DAY)
    store.set_status(cid, status)
    row = next(r for r in fleet(store, now=T0 + 91 * DAY) if r.serial == STEADY)
    assert (row.last, row.status, row.passed) == (last_finished, "accepted", True)
    assert row.age_days == pytest.approx((T0 + 91 * DAY - row.last_created) / DAY)
    assert (row.in_progress, row.in_progress_status, row.in_progress_station) == (cid, status, STATIONS[1])
    assert row.in_progress_created == T0 + 90 * DAY and row.calibrations == 4
    assert row.as_dict()["in_progress"] == cid
    # a robot whose calibrations are all finished has none in progress
    assert all(r.in_progress is None for r in fleet(store) if r.serial != STEADY)
    # once finished, it is the last calibration and nothing is in progress
    store.set_status(cid, "rejected")
    row = next(r for r in fleet(store) if r.serial == STEADY)
    assert (row.last, row.status, row.in_progress) == (cid, "rejected", None)


# --- one robot's history --------------------------------------------------------------------------------
def test_a_history_lists_every_calibration_oldest_first(store, built_fleet: Fleet):
    for serial, ids in built_fleet.campaigns.items():
        h = robot_history(store, serial)
        assert h.robot.serial == serial and h.robot.type == ROBOTS[serial]
        assert h.robot.controller is None  # not read from the controller yet
        assert [c.id for c in h.calibrations] == ids
        assert [c.created for c in h.calibrations] == sorted(c.created for c in h.calibrations)
        for c in h.calibrations:
            assert c.station == built_fleet.stations[c.id]
            assert c.model is not None and c.mark is None
            assert c.before_rms > 1e-3 and c.before_max >= c.before_rms  # millimetres before
            assert c.after_max >= c.after_rms
            assert c.good == (c.status == "accepted") == c.passed
        assert h.current == current_model(store, serial)[0]
    rejecting = robot_history(store, REJECTING)
    assert rejecting.current == built_fleet.campaigns[REJECTING][1]
    assert not rejecting.calibrations[-1].good


def test_the_hit_robot_is_flagged_and_the_others_are_not(store, built_fleet: Fleet):
    hit = robot_history(store, HIT_ROBOT)
    first, second = hit.comparisons
    ids = built_fleet.campaigns[HIT_ROBOT]
    assert (first.before, first.after, second.before, second.after) == (ids[0], ids[1], ids[1], ids[2])
    assert not first.moved and first.compared == 18  # the robot's own identifiable parameters
    [change] = second.changes
    assert change.name == HIT_PARAMETER and not change.angular
    assert change.delta == pytest.approx(HIT, abs=4 * change.sigma)  # what moved, by how much
    assert change.ratio > 20 and change.ratio == pytest.approx(abs(change.delta) / change.sigma)
    assert hit.moved == (second,)
    assert robot_history(store, STEADY).moved == ()
    rejecting = robot_history(store, REJECTING)
    assert len(rejecting.comparisons) == 1 and not rejecting.moved  # the rejected one is not compared
    assert len(robot_history(store, STEADY, k=1e-6).moved) == 2  # with k -> 0 noise is a "change"
    with pytest.raises(InputError, match="k must be"):
        robot_history(store, STEADY, k=0)


def test_the_fleets_geometry_changes_are_the_histories(store, built_fleet: Fleet):
    """`geometry_changes` reads at once, for the fleet report, what each robot's history says."""
    assert geometry_changes(store) == [(HIT_ROBOT, robot_history(store, HIT_ROBOT).moved[0])]
    hit = built_fleet.campaigns[HIT_ROBOT][2]
    created = robot_history(store, HIT_ROBOT).calibration(hit).created
    assert geometry_changes(store, since=created) == geometry_changes(store)
    assert geometry_changes(store, since=created + 1) == []
    assert len(geometry_changes(store, k=1e-6)) == 5  # every pair of good calibrations differs by noise


def test_parameters_are_compared_beyond_their_combined_uncertainty():
    def doc(**params):
        return {"parameters": [{"name": n, "value": v, "std": s} for n, (v, s) in params.items()]}

    a = doc(**{"joint2.tx": (0.0, 3e-6), "joint3.rx": (0.0, 1e-5), "joint4.tx": (0.0, 0.0),
               "flange.tz": (0.0, 1e-6), "smr.x": (0.0, 1e-6), "tracker.tx": (0.0, 1e-6),
               "joint5.tz": (0.0, 1e-6)})
    b = doc(**{"joint2.tx": (12.1e-6, 4e-6),  # |Δ| = 12.1 µm > 3·5 µm? no: 15 µm
               "joint3.rx": (-1e-4, 1e-5),  # 100 µrad > 3·14 µrad: changed
               "joint4.tx": (0.0, 0.0),  # no σ at all: not compared
               "flange.tz": (2e-5, 1e-6),  # changed
               "smr.x": (1.0, 1e-6), "tracker.tx": (1.0, 1e-6)})  # the station's, not compared
    compared, changes = compare_parameters(a, b)  # joint5.tz is missing from b: not compared
    assert compared == 3
    assert [c.name for c in changes] == ["flange.tz", "joint3.rx"]  # largest |Δ|/σ first
    assert changes[1].angular and changes[1].delta == pytest.approx(-1e-4)
    assert [c.name for c in compare_parameters(a, b, k=2)[1]] == ["flange.tz", "joint3.rx", "joint2.tx"]
    assert compare_parameters(a, b, prefixes=("smr",))[1][0].name == "smr.x"
    assert compare_parameters({}, {"parameters": "garbage"}) == (0, ())
    assert DEFAULT_K == 3.5


def test_only_the_parameters_of_a_model_document_are_parsed(store):
    from hil.store.fleet import _document_parameters

    doc = current_model(store, STEADY)[1]
    assert _document_parameters(json.dumps(doc)) == {"parameters": doc["parameters"]}
    reordered = {"covariance": doc["covariance"], **doc, "extra": float("nan")}  # the names come first
    assert _document_parameters(json.dumps(reordered, indent=2))["parameters"] == doc["parameters"]
    text = json.dumps({"note": 'a "parameters": [{"name": "x"}] string', "parameters": [{"name": "y"}]})
    assert _document_parameters(text) == {"parameters": [{"name": "y"}]}
    assert _document_parameters(json.dumps({"parameters": []})) == {"parameters": []}
    assert _document_parameters("not json") == {}


# --- marks ----------------------------------------------------------------------------------------------
def test_marking_bad_falls_back_to_the_previous_good_model_and_good_restores_it(store, built_fleet: Fleet):
    ids = built_fleet.campaigns[HIT_ROBOT]
    last_doc = current_model(store, HIT_ROBOT)
    assert last_doc[0] == ids[2] and last_doc[1]["format"] == "hil-model/1"

    bad = mark(store, ids[2], bad=True, reason="  dropped in transport  ", who="qa@plant")
    assert (bad.campaign, bad.bad, bad.reason, bad.who) == (ids[2], True, "dropped in transport", "qa@plant")
    cid, doc = current_model(store, HIT_ROBOT)
    assert cid == ids[1] and doc["parameters"] != last_doc[1]["parameters"]
    h = robot_history(store, HIT_ROBOT)
    assert h.current == ids[1] and h.calibrations[-1].mark == bad and not h.calibrations[-1].good
    assert h.moved == ()  # the calibration that saw the hit is not good any more: nothing to compare
    row = next(r for r in fleet(store) if r.serial == HIT_ROBOT)
    assert (row.last, row.marked_bad, row.current) == (ids[2], True, ids[1])

    good = mark(store, ids[2], bad=False, reason="checked: the hit was real, the calibration is right")
    assert good.id > bad.id
    assert current_model(store, HIT_ROBOT) == last_doc
    h = robot_history(store, HIT_ROBOT)
    assert h.current == ids[2] and h.calibrations[-1].mark == good and len(h.moved) == 1
    assert marks_in(store) == 2  # a journal: both judgements kept, the latest holds


def test_with_every_calibration_marked_bad_there_is_no_current_model(store, built_fleet: Fleet):
    for cid in built_fleet.campaigns[STEADY]:
        mark(store, cid, bad=True, reason="tracker out of calibration that month")
    assert current_model(store, STEADY) is None
    h = robot_history(store, STEADY)
    assert h.current is None and h.comparisons == ()
    row = next(r for r in fleet(store) if r.serial == STEADY)
    assert row.current is None and row.current_rms is None


def test_a_mark_needs_a_reason_and_a_campaign_and_writes_nothing_otherwise(store, built_fleet: Fleet):
    cid = built_fleet.campaigns[STEADY][0]
    for reason in ("", "   \n"):
        with pytest.raises(InputError, match="needs a reason"):
            mark(store, cid, bad=True, reason=reason)
    with pytest.raises(UnknownCampaignError, match="no campaign 'nope'"):
        mark(store, "nope", bad=True, reason="a reason")
    assert marks_in(store) == 0
    m = mark(store, built_fleet.anonymous, bad=True, reason="any campaign may be marked")
    assert m.who == f"{getpass.getuser()}@{socket.gethostname()}"


def test_an_unknown_serial_is_bad_input(store):
    for call in (robot_history, current_model):
        with pytest.raises(UnknownSerialError, match=r"no robot with serial '999'.*hil robots"):
            call(store, "999")
    assert issubclass(UnknownSerialError, InputError)


def test_the_calibrations_since_a_day(store, built_fleet: Fleet):
    everything = calibrations(store)
    assert len(everything) == 9 and built_fleet.anonymous not in {c.id for c in everything}
    recent = calibrations(store, since=T0 + 50 * DAY)
    assert {c.id for c in recent} == {ids[2] for ids in built_fleet.campaigns.values()}


# --- cost -----------------------------------------------------------------------------------------------
def test_the_fleet_listing_reads_no_model_and_a_fixed_number_of_queries(store, built_fleet: Fleet):
    """200 robots x 50 calibrations must list in well under a second: the listing never loads a model
    document and its query count does not grow with the fleet (no query per robot). The time itself is
    measured by ``bench/fleet.py``."""
    statements: list[str] = []
    with store.reading() as conn:
        engine = conn.engine

    def seen(conn, cursor, statement, parameters, context, executemany):
        statements.append(statement.lower())

    event.listen(engine, "before_cursor_execute", seen)
    try:
        fleet(store)
        small = len(statements)
        doc = current_model(store, STEADY)[1]
        for k in range(5):  # five more robots, two accepted calibrations each
            for j in range(2):
                cid = store.create_campaign({"station": {"name": "eol-cell-3"}, "robot": {"type": "ur5e"}},
                                            {"type": "ur5e", "serial": f"2024000{k}"}, now=T0 + j * DAY)
                store.save_model(cid, doc)
                store.save_validation(cid, {"rms": 2e-3, "max": 4e-3}, {"rms": 3e-5, "max": 6e-5}, True)
                store.set_status(cid, "accepted")
        statements.clear()
        rows = fleet(store)
    finally:
        event.remove(engine, "before_cursor_execute", seen)
    assert len(rows) == 8 and len(statements) == small
    assert not [s for s in statements if "doc" in s]
