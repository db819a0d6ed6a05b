"""The store's tables as SQLAlchemy Core metadata: one schema for SQLite and PostgreSQL.

This is the *current* shape (Alembic's head, `hil.store.migrations`); the migrations build it step by
step and are what creates and upgrades a database. Queries (`hil.store.rows`, `hil.store.queries`,
`hil.store.core`, `hil.store.fleet`) are written against these objects, so the same statement runs
on both engines.

Why the tables look as they do:

* Measurements are append-only (a pose measured twice keeps both rows; readers take the latest).
  The store is the record of what the instrument said, and a measurement is the one thing a run
  cannot cheaply redo.
* JSON columns (config, plan, q, p, model documents, events) are text holding what other parts of hil
  define and version themselves (``hil-model/1``, event dicts); the store only indexes what it
  queries on. Text rather than PostgreSQL's JSONB keeps the bytes identical on both engines, which the
  content hashes (models, validations) rely on.
* Times are seconds since the epoch (float): what the event log and the simulated clock use.
* Pose ``idx`` is unique within a campaign across roles: it is the pose's number in the plan.
* ``events.uid`` makes appending an event idempotent: a write retried after a lost database link,
  whose first COMMIT may or may not have landed, finds its own row instead of adding a second one.
* ``stream_chunks`` holds a sweep's two streams (``joints``: the controller's timestamps and
  actual_q; ``tracker``: the tracker's own stamps and points, a lost sample's point null) in chunks of
  a few hundred samples, one row each, committed as the sweep records them. A segment of the sweep is
  recorded under a ``take`` (one per attempt); its ``SweepSegmentDone`` event says which take is whole,
  so a segment cut short (Ctrl-C, ``kill -9``) is swept again under a new take and its partial rows are
  never read. ``session`` names the run that recorded it: the instruments' clocks may restart between
  two runs of a campaign.
* ``marks`` is a journal of judgements on a calibration (bad, with a reason; or good again): the
  current model of a robot is its newest accepted calibration whose latest mark is not bad.
"""

from __future__ import annotations

from sqlalchemy import (
    CheckConstraint,
    Column,
    Float,
    ForeignKey,
    Index,
    Integer,
    MetaData,
    PrimaryKeyConstraint,
    Table,
    Text,
    UniqueConstraint,
)

metadata = MetaData()

stations = Table(
    "stations", metadata,
    Column("id", Integer, primary_key=True),
    Column("name", Text, nullable=False, unique=True),
    Column("created", Float, nullable=False),
)

robots = Table(
    "robots", metadata,
    Column("id", Integer, primary_key=True),
    Column("serial", Text, nullable=False, unique=True),  # the controller's serial number
    Column("type", Text, nullable=False),  # catalog name (ur5e, ...)
    Column("model", Text, nullable=False, server_default=""),  # what the controller reports
    Column("software", Text, nullable=False, server_default=""),  # controller software version
    Column("first_seen", Float, nullable=False),
    Column("last_seen", Float, nullable=False),
    # JSON: the controller's own (factory) calibration when read from it; NULL until known
    Column("controller", Text),
)

campaigns = Table(
    "campaigns", metadata,
    Column("id", Text, primary_key=True),  # YYYYMMDD-HHMMSS-xxxx
    Column("station", Integer, ForeignKey("stations.id"), nullable=False),
    Column("robot", Integer, ForeignKey("robots.id")),  # NULL when the serial is unknown
    Column("robot_type", Text, nullable=False),
    Column("config", Text, nullable=False),  # JSON of the station configuration
    Column("plan", Text),  # JSON: selection summary (method, index, value, ...)
    Column("status", Text, nullable=False),  # created, running, paused, suspended, or a final one
    Column("detail", Text, nullable=False, server_default=""),
    Column("result", Text),  # JSON of RunFinished.result
    Column("software", Text, nullable=False, server_default=""),
    Column("created", Float, nullable=False),
    Column("updated", Float, nullable=False),
    Column("config_hash", Text, nullable=False, server_default=""),
    Column("measure_hash", Text, nullable=False, server_default=""),
    # JSON: the controller's own kinematic model this campaign ran with (v5; NULL: not reported)
    Column("controller", Text),
    # what the campaign is (v5): a 'calibration' (identifies a model) or a 'verification' (ISO 9283 test)
    Column("kind", Text, nullable=False, server_default="calibration"),
    Index("campaigns_created", "created"),
    Index("campaigns_resume", "config_hash", "created"),
    Index("campaigns_measure", "measure_hash", "created"),
    Index("campaigns_robot", "robot", "created"),
)

poses = Table(
    "poses", metadata,
    Column("campaign", Text, ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
    Column("idx", Integer, nullable=False),
    Column("role", Text, nullable=False),
    Column("target", Text, nullable=False),  # JSON, 6 joint angles (rad)
    Column("status", Text, nullable=False, server_default="planned"),
    Column("reason", Text, nullable=False, server_default=""),
    PrimaryKeyConstraint("campaign", "idx"),
    CheckConstraint("role IN ('bootstrap', 'calibration', 'validation')", name="poses_role"),
    CheckConstraint("status IN ('planned', 'measured', 'skipped')", name="poses_status"),
)

measurements = Table(
    "measurements", metadata,
    Column("id", Integer, primary_key=True),
    Column("campaign", Text, ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
    Column("pose", Integer, nullable=False),
    Column("role", Text, nullable=False),
    Column("q", Text, nullable=False),  # JSON, 6 joint angles averaged (rad)
    Column("q_spread", Text),
    Column("p", Text, nullable=False),  # JSON, SMR in the tracker frame (m)
    Column("p_spread", Text),
    Column("samples", Integer, nullable=False),
    Column("deviation", Float),
    Column("t", Float, nullable=False),
    UniqueConstraint("campaign", "pose", "t"),  # makes recording the same measurement idempotent
)

samples = Table(
    "samples", metadata,
    Column("measurement", Integer, ForeignKey("measurements.id", ondelete="CASCADE"), nullable=False),
    Column("kind", Text, nullable=False),
    Column("k", Integer, nullable=False),
    Column("value", Text, nullable=False),  # JSON vector
    PrimaryKeyConstraint("measurement", "kind", "k"),
    CheckConstraint("kind IN ('tracker', 'joints')", name="samples_kind"),
)

models = Table(
    "models", metadata,
    Column("id", Integer, primary_key=True),
    Column("campaign", Text, ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
    Column("doc", Text, nullable=False),  # the hil-model/1 document
    Column("sha256", Text, nullable=False),
    Column("rms", Float),
    Column("created", Float, nullable=False),
    UniqueConstraint("campaign", "sha256"),
)

validations = Table(
    "validations", metadata,
    Column("id", Integer, primary_key=True),
    Column("campaign", Text, ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
    Column("model", Integer, ForeignKey("models.id")),
    Column("before", Text, nullable=False),  # JSON {count, mean, rms, max}
    Column("after", Text, nullable=False),
    Column("passed", Integer, nullable=False),
    Column("rms", Float),  # after.rms, for listing
    Column("details", Text),  # JSON: ISO 9283 AP/RP, per-pose errors, ...
    Column("sha256", Text, nullable=False),
    Column("created", Float, nullable=False),
    UniqueConstraint("campaign", "sha256"),
)

events = Table(
    "events", metadata,
    Column("campaign", Text, ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
    Column("seq", Integer, nullable=False),
    Column("t", Float, nullable=False),
    Column("type", Text, nullable=False),
    Column("data", Text, nullable=False),  # Event.to_dict() JSON
    Column("uid", Text),  # one per recording: a retried write finds its row (NULL: before v4)
    PrimaryKeyConstraint("campaign", "seq"),
    Index("events_type", "campaign", "type"),
    Index("events_uid", "uid", unique=True),
)

leases = Table(
    "leases", metadata,
    Column("name", Text, primary_key=True),  # what is held: 'campaign:<id>' or 'robot:<serial>'
    Column("campaign", Text, nullable=False),  # the campaign its holder runs
    Column("owner", Text, nullable=False),  # JSON: host, pid, boot, started (hil.store.owner)
    Column("token", Text, nullable=False),  # random, one per claim: heartbeat and release touch only theirs
    Column("since", Float, nullable=False),
    Column("heartbeat", Float, nullable=False),
    Index("leases_token", "token"),
)

stream_chunks = Table(
    "stream_chunks", metadata,
    Column("campaign", Text, ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
    Column("segment", Integer, nullable=False),  # the sweep's segment (between two waypoints)
    Column("take", Text, nullable=False),  # the attempt that recorded it (random, one per attempt)
    Column("stream", Text, nullable=False),  # 'joints' or 'tracker'
    Column("chunk", Integer, nullable=False),  # 0, 1, ... within the take's stream
    Column("session", Text, nullable=False, server_default=""),  # the run that recorded it
    Column("count", Integer, nullable=False),
    Column("t0", Float, nullable=False),  # first and last stamp of the chunk (s, the stream's clock)
    Column("t1", Float, nullable=False),
    Column("data", Text, nullable=False),  # JSON {"t": [...], "v": [[...], ...]} (rad or m; null: lost)
    PrimaryKeyConstraint("campaign", "segment", "take", "stream", "chunk"),
)

marks = Table(
    "marks", metadata,
    Column("id", Integer, primary_key=True),
    Column("campaign", Text, ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
    Column("bad", Integer, nullable=False),  # 1: do not use this calibration; 0: good again
    Column("reason", Text, nullable=False),
    Column("who", Text, nullable=False, server_default=""),  # user@host that marked it
    Column("t", Float, nullable=False),
    Index("marks_campaign", "campaign", "id"),
)
