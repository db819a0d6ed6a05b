"""hil's store schema before Alembic, frozen: the hand-written steps that made versions 1 to 3.

Stores written by those versions exist on stations; tests build such files with `make_legacy` to
prove they upgrade in place (`hil.store.migrate` stamps them and carries on with Alembic). Never edit:
this is what old files look like.
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Callable, Sequence
from pathlib import Path

from hil.store.hashing import config_hash, measurement_hash

Step = Callable[[sqlite3.Connection], None]


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


def make_legacy(path: Path, version: int) -> Path:
    """An empty store file at `path` exactly as hil wrote it at schema `version` (1 to 3)."""
    conn = sqlite3.connect(path, isolation_level=None)
    try:
        conn.execute("PRAGMA journal_mode = WAL")
        conn.execute("BEGIN IMMEDIATE")
        for step in STEPS[:version]:
            step(conn)
        conn.execute(f"PRAGMA user_version = {int(version)}")
        conn.execute("COMMIT")
    finally:
        conn.close()
    return path
