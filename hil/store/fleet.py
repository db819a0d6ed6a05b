"""A plant's fleet: every robot (by serial), its calibrations, which model it carries now, and whether
its geometry moved between calibrations.

Definitions the CLI, the TUI and the fleet report share:

* A robot's **calibrations** are its campaigns (whatever their status), oldest first; each carries its
  latest validation (RMS and max before and after calibration on held-out poses), its latest model
  and its latest **mark**: the ``marks`` table is a journal of judgements (``bad`` with a reason, or
  good again), and the newest mark of a campaign is the one that holds.
* A robot's **last calibration** is its newest *finished* campaign (accepted, rejected or aborted:
  `hil.store.records.FINISHED`). A newest campaign that is not finished — running, or interrupted or
  failed and so resumable (a live status whose process is gone reads as interrupted) — is the robot's
  calibration **in progress**, shown as such, never as its last calibration nor among its results.
* A calibration is **good** when its status is ``accepted``, it has a model and its latest mark is not
  bad. A robot's **current model** is the latest model of its newest good calibration: marking that one
  bad falls back to the previous good one, marking it good again restores it.
* **Geometry changes**: for each pair of consecutive good calibrations, the robot's own geometry
  parameters (``joint<i>.*`` and ``flange.*`` of the model documents' ``parameters``, se(3) log
  coordinates from the nominal) whose change |Δ| exceeds k·sqrt(σa² + σb²) (k = 3 by default). The SMR
  offset and the tracker pose are left out: they describe the station's set-up (a nest remounted, a
  tracker moved), not the robot, and change between any two calibrations. A robot whose joint origins
  moved was hit or repaired.

Every read is SQL text of `hil.store.listing_sql`, which SQLite and PostgreSQL run unchanged, inside one
snapshot of the store it is given (`hil.store.listing.Reader`: the `Store`, or on a station's SQLite
file `hil.store.sqlite_reader.SqliteReader`, which needs no SQLAlchemy); `mark`, a write, goes through
the Store's SQLAlchemy Core. The fleet listing is a fixed number of queries,
whatever the fleet's size, and never reads a model document (only ids and the validations' small
JSON); `robot_history` reads the documents of one robot's good calibrations.
"""

from __future__ import annotations

import getpass
import itertools
import json
import math
import re
import socket
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import hil.store.listing_sql as sql
from hil.errors import InputError
from hil.store.json_columns import DamagedRowError, row_json, row_number
from hil.store.listing import Reader, Rows, UnknownCampaignError
from hil.store.listing_sql import ACCEPTED
from hil.store.owner import is_gone
from hil.store.records import FINISHED, INTERRUPTED, LIVE_STATES, _AsDict

if TYPE_CHECKING:
    from hil.store.core import Store

__all__ = ["ACCEPTED", "DEFAULT_K", "ROBOT_PARAMETERS", "calibrations", "compare_parameters", "current_model",
           "fleet", "geometry_changes", "mark", "robot_history"]

#: Default k of "beyond uncertainty": |Δ| > k·sqrt(σa² + σb²). Each of the ~18 robot parameters is
#: tested on its own, so k = 3 (0.27 % per parameter) would flag about 5 % of calibrations of arms that
#: did not change, hundreds a year in a plant. Bonferroni over 18 parameters at a 1 % false-alarm rate
#: per comparison gives Φ⁻¹(1 − 0.01/36) = 3.45; 3.5 keeps "moved" meaning moved.
DEFAULT_K = 3.5

#: Parameters of a model that describe the robot itself (see the module docstring).
ROBOT_PARAMETERS: tuple[str, ...] = ("joint", "flange")

_DAY = 86400.0


class UnknownSerialError(InputError):
    """No robot with that serial number in this database."""


# --- records ----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Mark(_AsDict):
    """One judgement on a calibration: bad (do not use its model) or good again, with why and by whom."""

    id: int
    campaign: str
    bad: bool
    reason: str
    who: str
    t: float  # seconds since the epoch


@dataclass(frozen=True)
class Calibration(_AsDict):
    """One campaign of a robot, as the fleet views show it. Lengths in metres."""

    id: str
    serial: str
    created: float
    station: str
    status: str  # a live status whose process is gone reads as ``interrupted``
    before_rms: float | None  # validation on held-out poses before calibration (the nominal arm)
    before_max: float | None
    after_rms: float | None  # ... and with the calibrated model
    after_max: float | None
    passed: bool | None  # None: not validated
    model: int | None  # id of its latest model, None without one
    mark: Mark | None  # its latest mark
    good: bool  # accepted, with a model, latest mark not bad: its model may be current

    @property
    def marked_bad(self) -> bool:
        return self.mark is not None and self.mark.bad

    @property
    def finished(self) -> bool:
        """Over (accepted, rejected, aborted); else in progress: running, or resumable."""
        return self.status in FINISHED


@dataclass(frozen=True)
class RobotRecord(_AsDict):
    serial: str
    type: str  # catalog name (ur5e, ...)
    model: str  # as the controller reports it
    software: str  # controller software version
    first_seen: float
    last_seen: float
    controller: dict[str, Any] | None  # the controller's factory calibration; None: not read


@dataclass(frozen=True)
class RobotSummary(_AsDict):
    """One line of ``hil robots``: the robot, its last calibration, its calibration in progress, and
    which model is current."""

    serial: str
    type: str
    model: str
    calibrations: int  # campaigns of this robot, finished or not
    last: str | None = None  # its newest finished campaign (None: none finished)
    last_created: float | None = None
    station: str | None = None  # where the last calibration ran
    status: str | None = None
    before_rms: float | None = None  # validation of the last calibration (m)
    after_rms: float | None = None
    passed: bool | None = None
    marked_bad: bool = False  # the last calibration's latest mark is bad
    age_days: float | None = None  # of the last calibration
    current: str | None = None  # the campaign whose model is current; None: no good calibration
    current_created: float | None = None
    current_rms: float | None = None  # validation RMS after calibration of the current model (m)
    # its newest campaign when that is not finished: running, or interrupted / failed (resumable)
    in_progress: str | None = None
    in_progress_created: float | None = None
    in_progress_status: str | None = None  # running, paused, ..., interrupted, failed
    in_progress_station: str | None = None


@dataclass(frozen=True)
class ParameterChange(_AsDict):
    """A parameter that changed between two calibrations by more than k combined standard deviations."""

    name: str
    before: float
    after: float
    delta: float  # after - before
    sigma: float  # sqrt(σa² + σb²)
    ratio: float  # |delta| / sigma

    @property
    def angular(self) -> bool:
        """A rotation (rad) rather than a length (m)."""
        return self.name.endswith((".rx", ".ry", ".rz"))


@dataclass(frozen=True)
class GeometryComparison(_AsDict):
    """Two consecutive good calibrations of one robot, and what changed beyond uncertainty."""

    before: str  # campaign ids
    after: str
    before_created: float
    after_created: float
    compared: int  # parameters present in both with a usable σ
    k: float
    changes: tuple[ParameterChange, ...]  # largest ratio first

    @property
    def moved(self) -> bool:
        return bool(self.changes)


@dataclass(frozen=True)
class Verification(_AsDict):
    """One ISO 9283 pose test (``hil verify``) of a robot: the worst pose's AP and RP of each mode."""

    id: str
    created: float
    station: str
    status: str
    cycles: int | None
    ap_max: Mapping[str, float]  # mode ("uncompensated", "compensated") -> worst pose AP (m)
    rp_max: Mapping[str, float]  # mode -> worst pose RP (m)


@dataclass(frozen=True)
class RobotHistory(_AsDict):
    """One robot: its record, every calibration oldest first, the current one, geometry changes, and
    its verifications (ISO 9283 pose tests) oldest first."""

    robot: RobotRecord
    calibrations: tuple[Calibration, ...]
    current: str | None  # campaign whose model is current
    comparisons: tuple[GeometryComparison, ...]  # consecutive good calibrations, oldest first
    verifications: tuple[Verification, ...] = ()

    @property
    def moved(self) -> tuple[GeometryComparison, ...]:
        """The comparisons that found the geometry changed."""
        return tuple(c for c in self.comparisons if c.moved)

    def calibration(self, campaign: str) -> Calibration | None:
        return next((c for c in self.calibrations if c.id == campaign), None)


# --- queries (SQL text: `hil.store.listing_sql`) ------------------------------------------------
def _loads(text: str | None) -> Any:
    if text is None:
        return None
    try:
        return json.loads(text)
    except ValueError:
        return None


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if math.isfinite(value) else None


def _stat(doc: Any, key: str) -> float | None:
    return _number(doc.get(key)) if isinstance(doc, Mapping) else None


def _calibrations(rows: Rows, where: str, params: dict[str, Any] | None = None) -> list[Calibration]:
    """The calibrations matching `where` (a condition on campaigns ``c``), oldest first, with their
    latest validation, model and mark; a fixed number of queries whatever their count."""
    found = rows(sql.CALIBRATIONS + where + sql.OLDEST_FIRST, params)
    live = [row[0] for row in found if row[4] in LIVE_STATES]
    gone = _gone(rows, live) if live else set()
    out = []
    for (cid, serial, created, station, status, before, after, passed, model, mark_id, bad, reason, who,
         t) in found:
        before, after = _loads(before), _loads(after)
        mark = None if mark_id is None else Mark(
            int(mark_id), cid, bool(bad), reason, who,
            float(row_number(t, table="marks", row=mark_id, column="t", campaign=cid)))
        out.append(Calibration(
            id=cid, serial=serial,
            created=float(row_number(created, table="campaigns", row=cid, column="created", campaign=cid)),
            station=station,
            status=INTERRUPTED if cid in gone else status,
            before_rms=_stat(before, "rms"), before_max=_stat(before, "max"),
            after_rms=_stat(after, "rms"), after_max=_stat(after, "max"),
            passed=None if passed is None else bool(passed), model=None if model is None else int(model),
            mark=mark,
            good=status == ACCEPTED and model is not None and not (mark is not None and mark.bad)))
    return out


def _gone(rows: Rows, campaigns: list[str]) -> set[str]:
    """Of campaigns in a live status, those whose run's process has certainly ended (`is_gone`)."""
    return {cid for cid, data in rows(*sql.run_started(campaigns))
            if is_gone((_loads(data) or {}).get("owner"))}


def _newest(query: str) -> str:
    """The condition "c is the newest per robot of `query`'s rows"."""
    return f"c.id IN ({sql.newest_per_robot(query)})"


def _robot(rows: Rows, serial: str, location: str) -> tuple[int, RobotRecord]:
    found = rows(sql.ROBOT, {"serial": serial})
    row = found[0] if found else None
    if row is None:
        known = rows(sql.ROBOT_COUNT)[0][0]
        hint = " (see `hil robots`)" if known else " (it has no robots with a known serial yet)"
        raise UnknownSerialError(f"{location}: no robot with serial {serial!r}{hint}")
    controller = _loads(row[7])
    return int(row[0]), RobotRecord(serial=row[1], type=row[2], model=row[3] or "",
                                    software=row[4] or "", first_seen=float(row[5]),
                                    last_seen=float(row[6]),
                                    controller=controller if isinstance(controller, dict) else None)


def fleet(store: Reader, *, station: str | None = None, now: float | None = None) -> list[RobotSummary]:
    """Every robot with a known serial, sorted by serial: its last (finished) calibration (campaign,
    time, station, status, validation RMS before/after, passed, age in days at `now`), its calibration
    in progress (its newest campaign when not finished: running or resumable) and its current model's
    campaign. `station` keeps the robots whose last calibration ran there (or, with none finished, whose
    calibration in progress runs there; InputError if no station has that name). Reads no model
    document."""
    now = time.time() if now is None else now
    with store.snapshot() as rows:
        if station is not None and not rows(sql.STATION_ID, {"station": station}):
            names = [n for (n,) in rows(sql.STATION_NAMES)]
            raise InputError(f"--station: no station named {station!r} in {store.location}"
                             + (f" (stations: {', '.join(names)})" if names else " (it has none yet)"))
        robots = rows(sql.ROBOTS)
        counts = {robot: n for robot, n in rows(sql.CALIBRATION_COUNTS)}
        last = {x.serial: x for x in _calibrations(rows, _newest(sql.FINISHED_CALIBRATIONS))}
        newest = {x.serial: x for x in _calibrations(rows, _newest(sql.ALL_CALIBRATIONS))}
        current = {x.serial: x for x in _calibrations(rows, _newest(sql.GOOD_CALIBRATIONS))}
    out = []
    for rid, serial, rtype, model in robots:
        x, cur = last.get(serial), current.get(serial)
        going = newest.get(serial)
        going = None if going is None or going.finished else going
        where_ = x.station if x is not None else going.station if going is not None else None
        if station is not None and where_ != station:
            continue
        fields: dict[str, Any] = {}
        if going is not None:
            fields.update(in_progress=going.id, in_progress_created=going.created,
                          in_progress_status=going.status, in_progress_station=going.station)
        if x is not None:
            fields.update(last=x.id, last_created=x.created, station=x.station, status=x.status,
                          before_rms=x.before_rms, after_rms=x.after_rms, passed=x.passed,
                          marked_bad=x.marked_bad, age_days=max(0.0, (now - x.created) / _DAY))
        if cur is not None:
            fields.update(current=cur.id, current_created=cur.created, current_rms=cur.after_rms)
        out.append(RobotSummary(serial=serial, type=rtype, model=model or "",
                                calibrations=int(counts.get(rid, 0)), **fields))
    return out


def calibrations(store: Reader, *, since: float | None = None) -> list[Calibration]:
    """Every calibration of a robot with a known serial, oldest first (those created at or after
    `since`, seconds since the epoch, when given): what the fleet report plots over time."""
    where, params = (sql.OF_FLEET, None) if since is None else (sql.OF_FLEET + sql.SINCE, {"since": since})
    with store.snapshot() as rows:
        return _calibrations(rows, where, params)


def _parameters(doc: Any, prefixes: tuple[str, ...]) -> dict[str, tuple[float, float]]:
    """name -> (value, std) of a model document's robot parameters with a finite value and σ."""
    out: dict[str, tuple[float, float]] = {}
    params = doc.get("parameters") if isinstance(doc, Mapping) else None
    for p in params if isinstance(params, list) else ():
        if not isinstance(p, Mapping) or not str(p.get("name", "")).startswith(prefixes):
            continue
        value, std = _number(p.get("value")), _number(p.get("std"))
        if value is not None and std is not None and std >= 0:
            out[str(p["name"])] = (value, std)
    return out


def _compare(a: Mapping[str, tuple[float, float]], b: Mapping[str, tuple[float, float]], k: float
             ) -> tuple[int, tuple[ParameterChange, ...]]:
    changes, compared = [], 0
    for name in a.keys() & b.keys():
        (va, sa), (vb, sb) = a[name], b[name]
        sigma = math.hypot(sa, sb)
        if sigma <= 0:
            continue
        compared += 1
        delta = vb - va
        if abs(delta) > k * sigma:
            changes.append(ParameterChange(name, va, vb, delta, sigma, abs(delta) / sigma))
    changes.sort(key=lambda ch: (-ch.ratio, ch.name))
    return compared, tuple(changes)


def compare_parameters(before: Mapping[str, Any], after: Mapping[str, Any], *, k: float = DEFAULT_K,
                       prefixes: tuple[str, ...] = ROBOT_PARAMETERS
                       ) -> tuple[int, tuple[ParameterChange, ...]]:
    """(parameters compared, those whose change exceeds k·sqrt(σa² + σb²), largest ratio first) of
    two model documents. A parameter missing from either, or with both σ zero, is not compared."""
    return _compare(_parameters(before, prefixes), _parameters(after, prefixes), k)


def _check_k(k: float) -> None:
    if not (k > 0 and math.isfinite(k)):
        raise InputError(f"k must be a positive number of standard deviations, got {k}")


#: Model documents read per query (a bound on the statement's parameters, whatever the fleet's size).
_BATCH = 500


_PARAMETERS_KEY = re.compile(r'"parameters"\s*:\s*')
_DECODER = json.JSONDecoder()


def _document_parameters(text: str) -> dict[str, Any]:
    """``{"parameters": [...]}`` of a model document's JSON text, parsing only that list when it can.

    A document is mostly its covariance matrix (hundreds of floats, which is what JSON parsing spends
    its time on), so comparing thousands of models parses just the value of a ``"parameters"`` key that
    is a list of objects with a ``name`` (the covariance block's own ``parameters`` is a list of names);
    a document without one is parsed whole. A quote inside a JSON string is escaped, so the pattern
    matches keys only."""
    for match in _PARAMETERS_KEY.finditer(text):
        try:
            value, _ = _DECODER.raw_decode(text, match.end())
        except ValueError:
            continue
        if isinstance(value, list) and value and all(isinstance(p, dict) and "name" in p for p in value):
            return {"parameters": value}
    doc = _loads(text)
    return doc if isinstance(doc, dict) else {}


def _model_parameters(rows: Rows, models: Iterable[int], prefixes: tuple[str, ...]
                      ) -> dict[int, dict[str, tuple[float, float]]]:
    """model id -> its robot parameters (`_parameters`), each document read and parsed once."""
    ids = sorted(set(models))
    out = {}
    for i in range(0, len(ids), _BATCH):
        for mid, doc in rows(*sql.model_docs(ids[i:i + _BATCH])):
            out[int(mid)] = _parameters(_document_parameters(doc), prefixes)
    return out


def _comparisons(good: list[tuple[str, float, int]], params: Mapping[int, Mapping[str, tuple[float, float]]],
                 k: float) -> list[GeometryComparison]:
    """Each consecutive pair of (campaign, created, model id) compared."""
    out = []
    for (a, t_a, m_a), (b, t_b, m_b) in itertools.pairwise(good):
        compared, changes = _compare(params.get(m_a, {}), params.get(m_b, {}), k)
        out.append(GeometryComparison(a, b, t_a, t_b, compared, k, changes))
    return out


def robot_history(store: Reader, serial: str, *, k: float = DEFAULT_K,
                  prefixes: tuple[str, ...] = ROBOT_PARAMETERS) -> RobotHistory:
    """One robot (UnknownSerialError if no robot has that serial): its record, every calibration oldest
    first, the campaign whose model is current, and the geometry changes between consecutive good
    calibrations (`compare_parameters` with `k`)."""
    _check_k(k)
    with store.snapshot() as rows:
        rid, robot = _robot(rows, serial, store.location)
        found = _calibrations(rows, sql.OF_ROBOT, {"robot": rid})
        good = [(x.id, x.created, x.model) for x in found if x.good and x.model is not None]
        params = _model_parameters(rows, (m for _, _, m in good), prefixes) if len(good) > 1 else {}
        checks = _verifications(rows, rid)
    return RobotHistory(robot=robot, calibrations=tuple(found), current=good[-1][0] if good else None,
                        comparisons=tuple(_comparisons(good, params, k)), verifications=checks)


def _verifications(rows: Rows, rid: int) -> tuple[Verification, ...]:
    """The robot's verification campaigns, oldest first, with the figures of their result document
    (``hil-verification/1``: ``results[mode].AP_max/RP_max``; none while unfinished)."""
    out = []
    for cid, created, station, status, result in rows(sql.VERIFICATIONS, {"robot": rid}):
        doc = _loads(result)
        results = doc.get("results") if isinstance(doc, Mapping) else None
        ap: dict[str, float] = {}
        rp: dict[str, float] = {}
        for mode, figures in (results.items() if isinstance(results, Mapping) else ()):
            if (a := _stat(figures, "AP_max")) is not None:
                ap[str(mode)] = a
            if (r := _stat(figures, "RP_max")) is not None:
                rp[str(mode)] = r
        cycles = doc.get("cycles") if isinstance(doc, Mapping) else None
        out.append(Verification(id=cid, created=float(created), station=station, status=status,
                                cycles=cycles if isinstance(cycles, int) else None, ap_max=ap, rp_max=rp))
    return tuple(out)


def geometry_changes(store: Reader, *, since: float | None = None, k: float = DEFAULT_K,
                     prefixes: tuple[str, ...] = ROBOT_PARAMETERS) -> list[tuple[str, GeometryComparison]]:
    """(serial, comparison) of every robot whose geometry moved between two consecutive good
    calibrations, the later one created at or after `since` (all when None), by serial and date: what
    `robot_history` reports for each robot, read for the whole fleet at once."""
    _check_k(k)
    by_robot: dict[str, list[tuple[str, float, int]]] = {}
    with store.snapshot() as rows:
        for serial, cid, created, model in rows(sql.GOOD_BY_SERIAL):
            by_robot.setdefault(serial, []).append((cid, float(created), int(model)))
        wanted = {}
        for serial, good in by_robot.items():
            pairs = [(a, b) for a, b in itertools.pairwise(good) if since is None or b[1] >= since]
            if pairs:
                wanted[serial] = pairs
        params = _model_parameters(rows, (x[2] for pairs in wanted.values() for pair in pairs for x in pair),
                                   prefixes)
    out = []
    for serial, pairs in wanted.items():
        for a, b in pairs:
            comparison = _comparisons([a, b], params, k)[0]
            if comparison.moved:
                out.append((serial, comparison))
    return out


def current_model(store: Reader, serial: str) -> tuple[str, dict[str, Any]] | None:
    """(campaign id, model document) of the robot's current model: the latest model of its newest
    accepted calibration whose latest mark is not bad; None if it has none. UnknownSerialError if no
    robot has that serial."""
    with store.snapshot() as rows:
        rid, _ = _robot(rows, serial, store.location)
        found = rows(sql.CURRENT_OF_ROBOT, {"robot": rid})
        if not found:
            return None
        cid, model = found[0]
        doc = rows(sql.MODEL_DOC, {"id": model})[0][0]
    value = row_json(doc, table="models", row=model, column="doc", campaign=str(cid))
    if not isinstance(value, dict):
        raise DamagedRowError(f"damaged store row: campaign {cid}, table models, id {model}: doc is not a "
                              "JSON object")
    return str(cid), value


def _who() -> str:
    """user@host of this process ("?" for what cannot be told)."""
    try:
        user = getpass.getuser()
    except (OSError, KeyError):  # no name for this uid (a container)
        user = "?"
    return f"{user}@{socket.gethostname() or '?'}"


def mark(store: Store, campaign: str, *, bad: bool, reason: str, who: str | None = None) -> Mark:
    """Append a mark to `campaign` (its exact id): ``bad=True`` takes its model out of use (the robot's
    current model falls back to the previous good calibration), ``bad=False`` makes it good again.
    `reason` is required (InputError when empty); `who` defaults to user@host.
    UnknownCampaignError if there is no such campaign."""
    text = (reason or "").strip()
    if not text:
        raise InputError("--reason: a mark needs a reason: say why the calibration is "
                         + ("bad" if bad else "good again"))
    who = (who or "").strip() or _who()
    t = time.time()
    from sqlalchemy import insert, select  # a write: the Store's SQLAlchemy is loaded already

    import hil.store.tables as tb

    c, mk = tb.campaigns, tb.marks
    with store.writing(f"mark campaign {campaign} {'bad' if bad else 'good'}") as conn:
        if conn.execute(select(c.c.id).where(c.c.id == campaign)).first() is None:
            raise UnknownCampaignError(f"{store.location}: no campaign {campaign!r}")
        result = conn.execute(insert(mk).values(campaign=campaign, bad=int(bool(bad)), reason=text,
                                                who=who, t=t))
        mid = int(result.inserted_primary_key[0])
    return Mark(mid, campaign, bool(bad), text, who, t)
