"""The SQL of the store's listings (``hil history``, ``hil show``, ``hil robots``, ``hil robot``, the
fleet report's reads): one text per query, in the SQL that SQLite and PostgreSQL both run unchanged.

Why text, not SQLAlchemy Core as the writes are: a listing on a station's SQLite file runs these very
strings through Python's own sqlite3 (`hil.store.sqlite_reader`), so it never imports SQLAlchemy,
whose import alone is most of a listing's start-up (bench/cli_startup.py); a PostgreSQL store, or a
file at another schema revision, runs the same strings through SQLAlchemy's ``text()``
(`hil.store.transactions.TransactionalStore.snapshot`). One source, no generated copy to keep in step:
the queries are written once, and tests/hil/store/test_sqlite_reader.py checks that both paths answer
alike. What keeps the text portable: standard joins, correlated scalar subqueries, ``row_number()
OVER`` (SQLite 3.25+), ``LIMIT``, ``LIKE … ESCAPE``, double-quoted identifiers where a name is a
keyword (``"before"``, ``"after"``), ``:name`` parameters (both drivers' named style), and lists
spelled out by `in_list` (neither sqlite3 nor ``text()`` expands a list on its own).

Constants of hil's own (states, kinds, roles) are written into the text from their Python definitions
(`hil.store.records`), never a value a user typed: those are parameters.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

from hil.store.records import CALIBRATION, FINISHED, LIVE_STATES, VERIFICATION

#: The status of a calibration whose model may be used (`hil.store.fleet.ACCEPTED`).
ACCEPTED = "accepted"


def literals(values: Iterable[str]) -> str:
    """``'a', 'b'``: hil's own constant strings as SQL literals, sorted (never user input)."""
    out = []
    for v in sorted(values):
        if "'" in v:
            raise ValueError(f"not a plain constant: {v!r}")
        out.append(f"'{v}'")
    return ", ".join(out)


def in_list(name: str, values: Sequence[Any]) -> tuple[str, dict[str, Any]]:
    """(``:name0, :name1, …``, their parameters): a list for ``IN (…)``, one parameter per value."""
    params = {f"{name}{i}": v for i, v in enumerate(values)}
    return ", ".join(f":{k}" for k in params), params


# --- campaigns (hil history, hil show) ---------------------------------------------------------------
def _poses(role: str, status: str | None = None) -> str:
    where = f" AND p.status = '{status}'" if status else ""
    return f"(SELECT count(*) FROM poses p WHERE p.campaign = c.id AND {role}{where})"


_CAMPAIGN_POSE = "p.role != 'bootstrap'"
_BOOTSTRAP_POSE = "p.role = 'bootstrap'"


def _latest(column: str, table: str) -> str:
    return f"(SELECT x.{column} FROM {table} x WHERE x.campaign = c.id ORDER BY x.id DESC LIMIT 1)"


#: One row per campaign, in `CampaignSummary`'s order (`hil.store.listing.summary` reads it). planned /
#: measured / skipped count the calibration and validation poses; the bootstrap's are counted apart;
#: the last column is the newest RunStarted event of a campaign in a live state (whose process may be
#: gone: then it reads as interrupted).
SUMMARY = (
    "SELECT c.id, c.created, c.updated, s.name, c.robot_type, COALESCE(r.serial, ''), c.status, "
    f"{_poses(_CAMPAIGN_POSE)}, {_poses(_CAMPAIGN_POSE, 'measured')}, {_poses(_CAMPAIGN_POSE, 'skipped')}, "
    f"{_latest('rms', 'models')}, {_latest('rms', 'validations')}, {_latest('passed', 'validations')}, "
    f"c.kind, {_poses(_BOOTSTRAP_POSE)}, {_poses(_BOOTSTRAP_POSE, 'measured')}, "
    f"CASE WHEN c.status IN ({literals(LIVE_STATES)}) THEN (SELECT e.data FROM events e "
    "WHERE e.campaign = c.id AND e.type = 'RunStarted' ORDER BY e.seq DESC LIMIT 1) ELSE NULL END "
    "FROM campaigns c JOIN stations s ON s.id = c.station LEFT OUTER JOIN robots r ON r.id = c.robot"
)
NEWEST_FIRST = " ORDER BY c.created DESC, c.id DESC"
HISTORY_AT_STATION = " WHERE s.name = :station"
ONE_CAMPAIGN = " WHERE c.id = :campaign"

LAST_ID = "SELECT id FROM campaigns ORDER BY created DESC, id DESC LIMIT 1"
ID = "SELECT id FROM campaigns WHERE id = :id"
#: campaign ids starting with :pattern (LIKE, with ``\\`` escaping ``%`` ``_`` and itself)
IDS_LIKE = "SELECT id FROM campaigns WHERE id LIKE :pattern ESCAPE '\\' ORDER BY created DESC LIMIT 6"

DETAIL = (
    "SELECT c.config, c.config_hash, c.plan, c.detail, c.result, c.software, c.robot_type, r.serial, "
    "r.model, r.software, c.controller FROM campaigns c LEFT OUTER JOIN robots r ON r.id = c.robot "
    "WHERE c.id = :campaign"
)
POSES = "SELECT idx, role, target, status, reason FROM poses WHERE campaign = :campaign"
BY_INDEX = " ORDER BY idx"
MEASUREMENTS = ("SELECT id, campaign, pose, role, q, p, q_spread, p_spread, samples, deviation, t "
                "FROM measurements WHERE campaign = :campaign")
OF_ROLE = " AND role = :role"
BY_ID = " ORDER BY id"
MODELS = "SELECT id, created, rms, doc FROM models WHERE campaign = :campaign ORDER BY id"
VALIDATIONS = ('SELECT id, created, model, "before", "after", passed, details FROM validations '
               "WHERE campaign = :campaign ORDER BY id")
EVENT_COUNTS = ("SELECT type, count(*) FROM events WHERE campaign = :campaign GROUP BY type "
                "ORDER BY min(seq)")


# --- the fleet (hil robots, hil robot, the fleet report) -------------------------------------------
def _latest_id(table: str) -> str:
    """The id of `table`'s newest row of campaign ``c`` (answered from its (campaign, …) index)."""
    return f"(SELECT max(x.id) FROM {table} x WHERE x.campaign = c.id)"


#: The calibrations matching a condition on ``c`` (appended after WHERE), oldest first, with their
#: latest validation, latest model id and latest mark. The latest model's id comes from the index
#: alone: a models row is its document (kilobytes).
CALIBRATIONS = (
    'SELECT c.id, r.serial, c.created, s.name, c.status, v."before", v."after", v.passed, '
    f"{_latest_id('models')}, mk.id, mk.bad, mk.reason, mk.who, mk.t "
    "FROM campaigns c JOIN stations s ON s.id = c.station JOIN robots r ON r.id = c.robot "
    f"LEFT OUTER JOIN validations v ON v.id = {_latest_id('validations')} "
    f"LEFT OUTER JOIN marks mk ON mk.id = {_latest_id('marks')} WHERE "
)
OLDEST_FIRST = " ORDER BY c.created, c.id"

#: (id, robot, created) of every calibration of a robot with a known serial.
ALL_CALIBRATIONS = ("SELECT c.id, c.robot, c.created FROM campaigns c "
                    f"WHERE c.robot IS NOT NULL AND c.kind = '{CALIBRATION}'")
#: ... of the finished ones (a robot's last calibration is the newest of these).
FINISHED_CALIBRATIONS = f"{ALL_CALIBRATIONS} AND c.status IN ({literals(FINISHED)})"
#: (id, robot, created, model) of every good calibration: accepted, with a model, its latest mark not bad.
GOOD_CALIBRATIONS = (
    f"SELECT c.id, c.robot, c.created, {_latest_id('models')} AS model FROM campaigns c "
    f"LEFT OUTER JOIN marks mk ON mk.id = {_latest_id('marks')} "
    f"WHERE c.robot IS NOT NULL AND c.kind = '{CALIBRATION}' AND c.status = '{ACCEPTED}' "
    "AND EXISTS (SELECT x.id FROM models x WHERE x.campaign = c.id) AND (mk.bad IS NULL OR mk.bad = 0)"
)


def newest_per_robot(query: str) -> str:
    """Of `query`'s (id, robot, created) rows, the ids of each robot's newest (ties: the larger id)."""
    return ("SELECT ranked.id FROM (SELECT sub.id, row_number() OVER (PARTITION BY sub.robot ORDER BY "
            f"sub.created DESC, sub.id DESC) AS n FROM ({query}) sub) ranked WHERE ranked.n = 1")


STATION_ID = "SELECT id FROM stations WHERE name = :station"
STATION_NAMES = "SELECT name FROM stations ORDER BY name"
ROBOTS = "SELECT id, serial, type, model FROM robots ORDER BY serial"
CALIBRATION_COUNTS = ("SELECT robot, count(*) FROM campaigns "
                      f"WHERE robot IS NOT NULL AND kind = '{CALIBRATION}' GROUP BY robot")
ROBOT = ("SELECT id, serial, type, model, software, first_seen, last_seen, controller FROM robots "
         "WHERE serial = :serial")
ROBOT_COUNT = "SELECT count(*) FROM robots"
OF_ROBOT = f"c.robot = :robot AND c.kind = '{CALIBRATION}'"
OF_FLEET = f"c.robot IS NOT NULL AND c.kind = '{CALIBRATION}'"
SINCE = " AND c.created >= :since"
VERIFICATIONS = (
    "SELECT c.id, c.created, s.name, c.status, c.result FROM campaigns c JOIN stations s ON s.id = c.station "
    f"WHERE c.robot = :robot AND c.kind = '{VERIFICATION}' ORDER BY c.created, c.id"
)
GOOD_BY_SERIAL = (f"SELECT r.serial, g.id, g.created, g.model FROM ({GOOD_CALIBRATIONS}) g "
                  "JOIN robots r ON r.id = g.robot ORDER BY r.serial, g.created, g.id")
CURRENT_OF_ROBOT = (f"SELECT g.id, g.model FROM ({GOOD_CALIBRATIONS} AND c.robot = :robot) g "
                    "ORDER BY g.created DESC, g.id DESC LIMIT 1")
MODEL_DOC = "SELECT doc FROM models WHERE id = :id"


def model_docs(ids: Sequence[int]) -> tuple[str, dict[str, Any]]:
    """(SQL, parameters) of the documents of models `ids`."""
    names, params = in_list("m", ids)
    return f"SELECT id, doc FROM models WHERE id IN ({names})", params


def run_started(campaigns: Sequence[str]) -> tuple[str, dict[str, Any]]:
    """(SQL, parameters) of (campaign, data) of each of `campaigns`' newest RunStarted event."""
    names, params = in_list("c", campaigns)
    return ("SELECT e.campaign, e.data FROM events e JOIN (SELECT campaign, max(seq) AS seq FROM events "
            f"WHERE campaign IN ({names}) AND type = 'RunStarted' GROUP BY campaign) n "
            "ON e.campaign = n.campaign AND e.seq = n.seq"), params
