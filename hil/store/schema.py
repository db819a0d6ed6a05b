"""The store's SQLite schema and its numbered upgrade steps.

The schema version lives in ``PRAGMA user_version`` (0 = empty file). `STEPS[i]` turns version ``i``
into version ``i + 1``; opening a database applies every missing step and the new ``user_version``
in ONE transaction, so an upgrade interrupted by a crash leaves the old version intact rather than a
half-migrated file. A step is a function of the connection, so it can rebuild data in Python as well
as run DDL (SQLite's DDL is transactional). Steps are append-only: once released, a step is never
edited; a change is a new step. A database newer than `SCHEMA_VERSION` is refused, because code that
does not know a column cannot keep its invariants.

Why the tables look as they do:

* Measurements are append-only (a pose measured twice keeps both rows; readers take the latest).
  The store is the record of what the instrument said, and a measurement is the one thing a run
  cannot cheaply redo.
* JSON columns (config, plan, q, p, model documents, events) hold what other parts of hil define and
  version themselves (``hil-model/1``, event dicts); the store only indexes what it queries on.
* Pose ``idx`` is unique within a campaign across roles: it is the pose's number in the plan.
"""

from __future__ import annotations

import hashlib
import json
import sqlite3
from collections.abc import Callable, Mapping, Sequence
from typing import Any

Step = Callable[[sqlite3.Connection], None]


def canonical_json(value: Any) -> str:
    """Deterministic compact JSON (sorted keys): equal values give equal text, hence equal hashes."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False)


def config_hash(config: Mapping[str, Any]) -> str:
    """sha256 of a station configuration, which is how a re-run finds the campaign it resumes.

    The ``store`` section is left out: where the results are kept does not change what is being
    calibrated, and moving the database must not orphan an unfinished campaign.
    """
    body = {k: v for k, v in config.items() if k != "store"}
    return hashlib.sha256(canonical_json(body).encode()).hexdigest()


def _script(*statements: str) -> Step:
    """A step made of SQL statements, run one by one inside the caller's transaction.

    (``executescript`` is avoided on purpose: it may COMMIT the open transaction first.)
    """

    def run(conn: sqlite3.Connection) -> None:
        for sql in statements:
            conn.execute(sql)

    return run


_V1 = _script(
    """CREATE TABLE stations (
        id      INTEGER PRIMARY KEY,
        name    TEXT NOT NULL UNIQUE,
        created REAL NOT NULL
    )""",
    """CREATE TABLE robots (
        id         INTEGER PRIMARY KEY,
        serial     TEXT NOT NULL UNIQUE,   -- the controller's serial number
        type       TEXT NOT NULL,          -- catalog name (ur5e, ...)
        model      TEXT NOT NULL DEFAULT '',  -- what the controller reports
        software   TEXT NOT NULL DEFAULT '',  -- controller software version
        first_seen REAL NOT NULL,
        last_seen  REAL NOT NULL
    )""",
    """CREATE TABLE campaigns (
        id       TEXT PRIMARY KEY,            -- YYYYMMDD-HHMMSS-xxxx
        station  INTEGER NOT NULL REFERENCES stations(id),
        robot    INTEGER REFERENCES robots(id),   -- NULL when the serial is unknown
        robot_type TEXT NOT NULL,
        config   TEXT NOT NULL,               -- JSON of the station configuration
        plan     TEXT,                        -- JSON: selection summary (method, index, value, ...)
        status   TEXT NOT NULL,               -- created, running, paused, suspended, or a final one
        detail   TEXT NOT NULL DEFAULT '',
        result   TEXT,                        -- JSON of RunFinished.result
        software TEXT NOT NULL DEFAULT '',
        created  REAL NOT NULL,
        updated  REAL NOT NULL
    )""",
    "CREATE INDEX campaigns_created ON campaigns (created)",
    """CREATE TABLE poses (
        campaign TEXT NOT NULL REFERENCES campaigns(id) ON DELETE CASCADE,
        idx      INTEGER NOT NULL,
        role     TEXT NOT NULL CHECK (role IN ('bootstrap', 'calibration', 'validation')),
        target   TEXT NOT NULL,               -- JSON, 6 joint angles (rad)
        status   TEXT NOT NULL DEFAULT 'planned' CHECK (status IN ('planned', 'measured', 'skipped')),
        reason   TEXT NOT NULL DEFAULT '',
        PRIMARY KEY (campaign, idx)
    ) WITHOUT ROWID""",
    """CREATE TABLE measurements (
        id        INTEGER PRIMARY KEY,
        campaign  TEXT NOT NULL REFERENCES campaigns(id) ON DELETE CASCADE,
        pose      INTEGER NOT NULL,
        role      TEXT NOT NULL,
        q         TEXT NOT NULL,              -- JSON, 6 joint angles averaged (rad)
        q_spread  TEXT,
        p         TEXT NOT NULL,              -- JSON, SMR in the tracker frame (m)
        p_spread  TEXT,
        samples   INTEGER NOT NULL,
        deviation REAL,
        t         REAL NOT NULL,
        UNIQUE (campaign, pose, t)            -- makes recording the same measurement idempotent
    )""",
    """CREATE TABLE samples (
        measurement INTEGER NOT NULL REFERENCES measurements(id) ON DELETE CASCADE,
        kind        TEXT NOT NULL CHECK (kind IN ('tracker', 'joints')),
        k           INTEGER NOT NULL,
        value       TEXT NOT NULL,            -- JSON vector
        PRIMARY KEY (measurement, kind, k)
    ) WITHOUT ROWID""",
    """CREATE TABLE models (
        id       INTEGER PRIMARY KEY,
        campaign TEXT NOT NULL REFERENCES campaigns(id) ON DELETE CASCADE,
        doc      TEXT NOT NULL,               -- the hil-model/1 document
        sha256   TEXT NOT NULL,
        rms      REAL,
        created  REAL NOT NULL,
        UNIQUE (campaign, sha256)
    )""",
    """CREATE TABLE validations (
        id       INTEGER PRIMARY KEY,
        campaign TEXT NOT NULL REFERENCES campaigns(id) ON DELETE CASCADE,
        model    INTEGER REFERENCES models(id),
        before   TEXT NOT NULL,               -- JSON {count, mean, rms, max}
        after    TEXT NOT NULL,
        passed   INTEGER NOT NULL,
        rms      REAL,                        -- after.rms, for listing
        details  TEXT,                        -- JSON: ISO 9283 AP/RP, per-pose errors, ...
        sha256   TEXT NOT NULL,
        created  REAL NOT NULL,
        UNIQUE (campaign, sha256)
    )""",
    """CREATE TABLE events (
        campaign TEXT NOT NULL REFERENCES campaigns(id) ON DELETE CASCADE,
        seq      INTEGER NOT NULL,
        t        REAL NOT NULL,
        type     TEXT NOT NULL,
        data     TEXT NOT NULL,               -- Event.to_dict() JSON
        PRIMARY KEY (campaign, seq)
    ) WITHOUT ROWID""",
)


def _v2(conn: sqlite3.Connection) -> None:
    """v2: a config hash on campaigns (filled in for existing ones) and the indexes resume needs."""
    conn.execute("ALTER TABLE campaigns ADD COLUMN config_hash TEXT NOT NULL DEFAULT ''")
    rows = conn.execute("SELECT id, config FROM campaigns").fetchall()
    for cid, config in rows:
        conn.execute("UPDATE campaigns SET config_hash = ? WHERE id = ?",
                     (config_hash(json.loads(config)), cid))
    conn.execute("CREATE INDEX campaigns_resume ON campaigns (config_hash, created)")
    conn.execute("CREATE INDEX events_type ON events (campaign, type)")


STEPS: Sequence[Step] = (_V1, _v2)
SCHEMA_VERSION = len(STEPS)


def migrate(conn: sqlite3.Connection, where: str, target: int = SCHEMA_VERSION) -> int:
    """Bring the database to version `target` in one transaction; returns the version found.

    `conn` must be in autocommit mode (``isolation_level=None``); `where` names the file in errors.
    The version is re-read after taking the write lock, so two processes opening an old database at
    once upgrade it exactly once.
    """
    from hil.errors import InputError

    found = conn.execute("PRAGMA user_version").fetchone()[0]
    if found > SCHEMA_VERSION:
        raise InputError(f"{where}: database schema version {found} is newer than this hil supports "
                         f"({SCHEMA_VERSION}); upgrade hil to read it")
    if found >= target:
        return int(found)
    conn.execute("BEGIN IMMEDIATE")
    try:
        found = conn.execute("PRAGMA user_version").fetchone()[0]
        if found == 0:
            tables = conn.execute("SELECT count(*) FROM sqlite_master").fetchone()[0]
            if tables:
                raise InputError(f"{where}: an SQLite database, but not a hil store")
        for step in STEPS[found:target]:
            step(conn)
        conn.execute(f"PRAGMA user_version = {int(max(found, target))}")
        conn.execute("COMMIT")
    except BaseException:
        if conn.in_transaction:
            conn.execute("ROLLBACK")
        raise
    return int(found)
