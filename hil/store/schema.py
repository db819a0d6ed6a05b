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


# What does not change what a campaign measures, so a re-run that differs only there resumes it:
# how hil reaches the devices and how long it waits for them. ``None`` drops the whole section.
#   robot.address   — the arm is identified by its serial, which `find_resumable` matches instead
#                     (and, when the serial is unknown, it compares the address itself);
#   tracker.url     — a serial port renamed (/dev/ttyUSB0 -> /dev/ttyUSB1), a socket:// or tcp:// address
#                     changed: the same instrument on another cable or network;
#   tracker.baudrate, tracker.parity — settings of that cable, not of the measurement;
#   tracker.timeout, tracker.warmup, timeouts.* — how long to wait for a reply, a warm laser, a
#                     move, a relock: a longer wait measures the same point (a skipped pose is
#                     recorded as skipped, not measured differently);
#   store.*         — where the results are kept.
# Everything else stays: the robot type and motion settings, the tracker's protocol (GeoCOM and emScon
# measure differently: a stationary measuring time, a reflector choice), its position guess and the
# atmospheric correction (which change every distance), the SMR, the keep-in box, the campaign's
# counts, seed and acceptance. A value starting with ``sim:`` is kept even in a dropped key: the
# simulated station identifies itself there by what it simulates (seed, truth), not where it listens.
# Changing this table changes the hashes: it needs a new schema step recomputing ``measure_hash``.
MEASUREMENT_IGNORED: Mapping[str, tuple[str, ...] | None] = {
    "robot": ("address",),
    "tracker": ("url", "baudrate", "parity", "timeout", "warmup"),
    "timeouts": None,
    "store": None,
}


def measurement_identity(config: Mapping[str, Any]) -> dict[str, Any]:
    """The station configuration without what does not change the measurement (`MEASUREMENT_IGNORED`)."""
    body: dict[str, Any] = {}
    for section, values in config.items():
        if section in MEASUREMENT_IGNORED and MEASUREMENT_IGNORED[section] is None:
            continue
        dropped = MEASUREMENT_IGNORED.get(section) or ()
        if isinstance(values, Mapping):
            values = {k: v for k, v in values.items()
                      if k not in dropped or (isinstance(v, str) and v.startswith("sim:"))}
        body[section] = values
    return body


def measurement_hash(config: Mapping[str, Any]) -> str:
    """sha256 of `measurement_identity`: how a re-run finds the campaign it resumes, so the poses
    already measured are reused when only a connection address, a timeout or the store changed."""
    return hashlib.sha256(canonical_json(measurement_identity(config)).encode()).hexdigest()


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


def _v3(conn: sqlite3.Connection) -> None:
    """v3: leases (`hil.store.leases`: one process per campaign, one campaign per robot) and a
    measurement hash on campaigns (filled in for existing ones), which resume matches instead of
    the config hash, so a changed tracker URL or timeout no longer orphans an unfinished campaign.

    Plain SQL that PostgreSQL runs as well: leases are taken with INSERT ... ON CONFLICT DO NOTHING
    and a conditional UPDATE under the unique ``name``."""
    conn.execute("""CREATE TABLE leases (
        name      TEXT PRIMARY KEY,   -- what is held: 'campaign:<id>' or 'robot:<serial>'
        campaign  TEXT NOT NULL,      -- the campaign its holder runs
        owner     TEXT NOT NULL,      -- JSON: host, pid, boot, started (hil.store.owner)
        token     TEXT NOT NULL,      -- random, one per claim: heartbeat and release touch only theirs
        since     REAL NOT NULL,
        heartbeat REAL NOT NULL
    )""")
    conn.execute("CREATE INDEX leases_token ON leases (token)")
    conn.execute("ALTER TABLE campaigns ADD COLUMN measure_hash TEXT NOT NULL DEFAULT ''")
    rows = conn.execute("SELECT id, config FROM campaigns").fetchall()
    for cid, config in rows:
        conn.execute("UPDATE campaigns SET measure_hash = ? WHERE id = ?",
                     (measurement_hash(json.loads(config)), cid))
    conn.execute("CREATE INDEX campaigns_measure ON campaigns (measure_hash, created)")


STEPS: Sequence[Step] = (_V1, _v2, _v3)
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
