"""The `Store`: the one object callers get for a hil database — campaigns, poses, measurements,
models, validations, events and leases, on SQLite or PostgreSQL.

One schema, two engines (`hil.store.tables`, migrated by Alembic: `hil.store.migrate`), and every
query written once — the writes in SQLAlchemy Core, the listings' reads as SQL text both engines share
(`hil.store.listing_sql`) — so both run the same statements. `Store` is put together
from the store's parts, each in a module of its own:

* `hil.store.transactions` — opening the database, its transactions, durability and threads, and
  waiting out a lost link (`TransactionalStore`, the base of the others);
* `hil.store.queries` — the read side: the history, a campaign's record, poses, measurements
  (`hil.store.listing`, which `hil.store.sqlite_reader` shares), events;
* `hil.store.recorder` — the event recorder the engine subscribes: each event logged with its rows;
* `hil.store.rows` — the rows a write adds inside its transaction, shared by the recorder and the
  direct methods here, so both write alike;
* this module — what is left to `Store` itself: a campaign's life (created, its status, found again
  to resume), its plan, the direct writes of measurements, models and validations, and the leases
  that let one process run a campaign and drive its arm (`hil.store.leases` says why).
"""

from __future__ import annotations

import json
import secrets
import time
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from sqlalchemy import Connection, select

import hil.store.tables as tb
from hil.campaign.ids import new_campaign_id
from hil.errors import InputError
from hil.store.hashing import measurement_hash
from hil.store.leases import LEASE_TTL, Lease, LeaseRefused, describe_holder, holder_gone
from hil.store.owner import this_process
from hil.store.queries import StoreQueries, UnknownCampaignError
from hil.store.recorder import EventRecorder
from hil.store.records import FINISHED, ROLES, PlannedPose, RobotIdentity
from hil.store.rows import (
    dialect_insert,
    dumps,
    insert_campaign,
    insert_measurement,
    insert_model,
    insert_validation,
    require_campaign,
    row_json,
    set_status,
    skip_pose,
    touch,
    vector,
)
from hil.store.sqlite_errors import CorruptStoreError, StoreError, StoreUnavailable

__all__ = ["CorruptStoreError", "Store", "StoreError", "StoreUnavailable", "UnknownCampaignError"]


class Store(EventRecorder, StoreQueries):
    """A hil database. ``Store(location)`` does no I/O; `connect` (or ``with``, or `Store.open`) does.

    `location` is a file path (SQLite) or a ``postgresql://`` URL. Typical use::

        with Store.open(config=cfg) as store:
            cid = store.find_resumable(cfg, robot.serial) or store.create_campaign(cfg, robot, plan)
            bus.subscribe(store.as_subscriber(), critical=True)
    """

    # --- campaigns ----------------------------------------------------------------------------
    def create_campaign(self, config: Any, robot: RobotIdentity | Mapping[str, Any] | str | None = None,
                        plan: Mapping[str, Any] | None = None, *, now: float | None = None) -> str:
        """Start a campaign record (status ``created``) and return its id.

        `config` is a StationConfig or its ``as_dict()``; it is stored whole (the campaign must be
        reproducible from the database alone) with its `config_hash`, and the `measurement_hash`
        `find_resumable` matches.
        `robot` defaults to the config's robot type with an unknown serial.
        """
        now = time.time() if now is None else now
        cid = new_campaign_id(now)
        return self._write("create a campaign",
                           lambda conn: insert_campaign(conn, config, robot, plan, now, cid))

    def set_status(self, campaign: str, status: str, detail: str | None = None,
                   result: Mapping[str, Any] | None = None) -> None:
        """Set a campaign's status (and optionally its detail text and result JSON)."""
        now = time.time()
        self._write("set the status",
                    lambda conn: set_status(conn, campaign, status, detail, result, now, self.location))

    def set_controller(self, serial: str, controller: Mapping[str, Any]) -> None:
        """Keep what a robot's controller says about its own (factory) calibration."""
        r = tb.robots

        def body(conn: Connection) -> None:
            if conn.execute(r.update().where(r.c.serial == serial)
                            .values(controller=dumps(controller))).rowcount == 0:
                raise StoreError(f"{self.location}: no robot {serial!r}")

        self._write("record the controller's calibration", body)

    def find_resumable(self, config: Any = None, robot_serial: str | None = None, *,
                       config_sha256: str | None = None) -> str | None:
        """The newest unfinished campaign that measures what `config` would, or None.

        Unfinished means a status outside `FINISHED` (so a killed run, and one ended by a hardware
        fault, are resumable; an accepted, rejected or aborted one is not). "Measures what `config`
        would" is the `measurement_hash`: a changed tracker URL, robot address, timeout or store path
        resumes the campaign, its poses already measured reused (`hil.store.hashing.MEASUREMENT_IGNORED`
        says which keys and why). Give `robot_serial` whenever it is known: an end-of-line cell runs
        the same config on robot after robot, and resuming another arm's campaign would mix two
        robots' measurements. With a serial, only a campaign of that serial matches; without one,
        the robot address is what tells the arm, so it must match too. `config_sha256` instead of a
        config matches the exact configuration (`config_hash`).

        A campaign found here may be running in another process: `claim` it before resuming.
        """
        c, r = tb.campaigns, tb.robots
        if config_sha256 is not None:
            column, key, address = c.c.config_hash, config_sha256, None
        elif config is None:
            raise ValueError("find_resumable needs a config or a config hash")
        else:
            values = config.as_dict() if hasattr(config, "as_dict") else config
            column, key = c.c.measure_hash, measurement_hash(values)
            address = None if robot_serial else (values.get("robot") or {}).get("address")
        q = (select(c.c.id, c.c.config).select_from(c.outerjoin(r, r.c.id == c.c.robot))
             .where(column == key, c.c.status.not_in(sorted(FINISHED))))
        if robot_serial:
            q = q.where(r.c.serial == robot_serial)
        q = q.order_by(c.c.created.desc(), c.c.id.desc())
        for cid, stored in self._query(lambda conn: conn.execute(q).all()):
            stored_config = row_json(stored, table="campaigns", row=cid, column="config", campaign=str(cid))
            if address is None or ((stored_config or {}).get("robot") or {}).get("address") == address:
                return str(cid)
        return None

    def unfinished_campaigns(self) -> list[str]:
        """Every unfinished campaign, newest first, each config read through the damaged-row check:
        what ``--resume`` could continue, known before a simulated station's seconds of start-up (a
        damaged row among them is named, `row_json`)."""
        c = tb.campaigns
        q = (select(c.c.id, c.c.config).where(c.c.status.not_in(sorted(FINISHED)))
             .order_by(c.c.created.desc(), c.c.id.desc()))
        found = []
        for cid, stored in self._query(lambda conn: conn.execute(q).all()):
            row_json(stored, table="campaigns", row=cid, column="config", campaign=str(cid))
            found.append(str(cid))
        return found

    # --- leases (hil.store.leases: one process per campaign, one campaign per robot) ----------------
    def claim(self, campaign: str, robot_serial: str = "", *, ttl: float = LEASE_TTL,
              heartbeat: bool = True) -> Lease:
        """Take the leases of `campaign` and of the robot `robot_serial` ("" = unknown: none) for this
        process, in one transaction, or raise LeaseRefused naming the live process that holds either.

        A lease whose holder is gone (killed, a power cut; `holder_gone`) is taken over: its campaign
        is resumable. InputError if the campaign is finished (accepted, rejected, aborted: nothing
        left to run), UnknownCampaignError if there is none. Release the lease when the run ends.
        """
        token = secrets.token_hex(16)

        def body(conn: Connection) -> tuple[str, ...]:
            c = tb.campaigns
            status = conn.execute(select(c.c.status).where(c.c.id == campaign)).scalar()
            if status is None:
                raise UnknownCampaignError(f"{self.location}: no campaign {campaign!r}")
            mine = self._mine(conn, token)
            if mine:
                return mine  # committed before the link dropped
            if status in FINISHED:
                raise InputError(f"campaign {campaign} is already {status}: there is nothing left to "
                                 "run (start a new one)")
            return self._take_leases(conn, campaign, robot_serial, token, time.time(), ttl,
                                     f"campaign {campaign}")

        names = self._write(f"claim campaign {campaign}", body)
        return Lease(self, campaign, token, names, ttl=ttl, heartbeat=heartbeat)

    def claim_new(self, config: Any, robot: RobotIdentity | Mapping[str, Any] | str | None = None,
                  plan: Mapping[str, Any] | None = None, *, ttl: float = LEASE_TTL,
                  heartbeat: bool = True) -> Lease:
        """`create_campaign` and `claim` in one transaction: a robot driven by another live campaign
        refuses (LeaseRefused) and leaves no empty campaign behind. ``lease.campaign`` is the new id."""
        token, now = secrets.token_hex(16), time.time()
        serial = RobotIdentity.coerce(robot).serial if robot is not None else ""
        cid = new_campaign_id(now)
        made: dict[str, str] = {}

        def body(conn: Connection) -> tuple[str, ...]:
            mine = self._mine(conn, token)
            if mine:
                return mine
            made["id"] = insert_campaign(conn, config, robot, plan, now, cid)
            return self._take_leases(conn, made["id"], serial, token, now, ttl, "")

        names = self._write("create a campaign", body)
        return Lease(self, made["id"], token, names, ttl=ttl, heartbeat=heartbeat)

    @staticmethod
    def _mine(conn: Connection, token: str) -> tuple[str, ...]:
        """The lease rows carrying `token` (a claim whose COMMIT landed before the link dropped)."""
        le = tb.leases
        return tuple(sorted(conn.execute(select(le.c.name).where(le.c.token == token)).scalars(),
                            key=lambda n: not n.startswith("campaign:")))

    def check_claim(self, campaign: str | None, robot_serial: str = "", *,
                    ttl: float = LEASE_TTL) -> None:
        """Raise LeaseRefused if `claim` (`claim_new` when `campaign` is None) would be refused now:
        a UI asks before offering a resume or starting a run. Writes nothing."""
        now = time.time()
        le = tb.leases
        names = (([f"campaign:{campaign}"] if campaign else [])
                 + ([f"robot:{robot_serial}"] if robot_serial else []))
        for name in names:
            row = self._query(lambda conn, name=name: conn.execute(
                select(le.c.campaign, le.c.owner, le.c.since, le.c.heartbeat, le.c.token)
                .where(le.c.name == name)).first())
            if row is not None and not holder_gone(json.loads(row[1]), row[3], now, ttl, row[4]):
                raise LeaseRefused(self._refusal(name, campaign and f"campaign {campaign}", row[0],
                                                 json.loads(row[1]), row[2]))

    def _take_leases(self, conn: Connection, campaign: str, robot_serial: str, token: str,
                     now: float, ttl: float, mine: str) -> tuple[str, ...]:
        """Insert or take over (compare-and-set) each lease row, inside the caller's transaction;
        LeaseRefused (rolling the whole transaction back) at the first one a live process holds.
        `mine` names the campaign in that message ("" for a new one: its id is rolled back too)."""
        le = tb.leases
        owner = dumps(this_process())
        names = (f"campaign:{campaign}",) + ((f"robot:{robot_serial}",) if robot_serial else ())
        for name in names:
            for _ in range(3):  # PostgreSQL (read committed): a row may vanish between two statements
                if conn.execute(dialect_insert(conn, le).values(
                        name=name, campaign=campaign, owner=owner, token=token, since=now, heartbeat=now)
                        .on_conflict_do_nothing(index_elements=["name"])
                        .returning(le.c.name)).first() is not None:
                    break
                held = conn.execute(select(le.c.campaign, le.c.owner, le.c.token, le.c.since,
                                           le.c.heartbeat).where(le.c.name == name)).first()
                if held is None:
                    continue
                holder, held_owner, held_token, since, beat = held
                if not holder_gone(json.loads(held_owner), beat, now, ttl, held_token):
                    raise LeaseRefused(self._refusal(name, mine, holder, json.loads(held_owner), since))
                if conn.execute(  # the holder is gone: take it over, unless someone just did
                        le.update().where(le.c.name == name, le.c.token == held_token)
                        .values(campaign=campaign, owner=owner, token=token, since=now,
                                heartbeat=now)).rowcount == 1:
                    break
            else:
                raise LeaseRefused(f"{mine or 'a new campaign'}: {name} keeps changing hands; try again")
        return names

    @staticmethod
    def _refusal(name: str, mine: str, holder: str, owner: Any, since: float) -> str:
        """The one line a refused claim says: what is held, by which campaign and process, since when."""
        who = describe_holder(owner, since)
        if name.startswith("robot:"):
            return (f"robot {name[len('robot:'):]} is being driven by campaign {holder} ({who}): "
                    f"{mine or 'a new campaign'} cannot use it until that run ends")
        return (f"campaign {holder} is being run by {who}: wait for that run to end, or stop it "
                "(a campaign whose process has ended is resumed)")

    def renew_lease(self, lease: Lease) -> bool:
        """The heartbeat: True while every row of `lease` still carries its token. One try (no wait on
        a lost link: the next beat tries again)."""
        le = tb.leases
        with self.writing("renew a lease") as conn:
            count = conn.execute(le.update().where(le.c.token == lease.token)
                                 .values(heartbeat=time.time())).rowcount
        return count == len(lease.names)

    def release_lease(self, lease: Lease) -> None:
        """Give up `lease` (rows taken over meanwhile carry another token and stay)."""
        le = tb.leases
        with self.writing("release a lease") as conn:
            conn.execute(le.delete().where(le.c.token == lease.token))

    def leases(self) -> list[dict[str, Any]]:
        """Every lease row (name, campaign, owner, since, heartbeat): who holds what, for tests and UIs."""
        le = tb.leases
        rows = self._query(lambda conn: conn.execute(
            select(le.c.name, le.c.campaign, le.c.owner, le.c.since, le.c.heartbeat)
            .order_by(le.c.name)).all())
        return [{"name": n, "campaign": c, "owner": json.loads(o), "since": s, "heartbeat": h}
                for n, c, o, s, h in rows]

    # --- poses and measurements ---------------------------------------------------------------
    def save_plan(self, campaign: str,
                  poses: Iterable[PlannedPose | tuple[int, str, Sequence[float]]],
                  plan: Mapping[str, Any] | None = None) -> None:
        """Record the poses to visit (index, role, target q), and optionally the plan summary.

        May be called again (bootstrap poses first, the selected ones later; or a new selection):
        a pose still ``planned`` is replaced, one already measured or skipped must not change, as
        its measurement was taken at that target (StoreError).
        """
        rows = []
        for pose in poses:
            index, role, target = ((pose.index, pose.role, pose.target)
                                   if isinstance(pose, PlannedPose) else pose)
            if role not in ROLES:
                raise StoreError(f"pose {index}: role must be one of {', '.join(ROLES)}, got {role!r}")
            rows.append((int(index), role, dumps(vector(target, 6, f"pose {index} target"))))
        p = tb.poses

        def body(conn: Connection) -> None:
            require_campaign(conn, campaign, self.location)
            old = {i: (role, target, status) for i, role, target, status in conn.execute(
                select(p.c.idx, p.c.role, p.c.target, p.c.status).where(p.c.campaign == campaign))}
            new: dict[int, dict[str, Any]] = {}
            for index, role, target in rows:
                was = old.get(index)
                if was is None or index in new:
                    new[index] = {"campaign": campaign, "idx": index, "role": role, "target": target}
                elif was[2] == "planned":
                    if (was[0], was[1]) != (role, target):
                        conn.execute(p.update().where(p.c.campaign == campaign, p.c.idx == index)
                                     .values(role=role, target=target))
                elif (was[0], json.loads(was[1])) != (role, json.loads(target)):
                    raise StoreError(f"campaign {campaign}: pose {index} is already {was[2]}; "
                                     "its target and role cannot change")
            if new:
                conn.execute(p.insert(), list(new.values()))
            if plan is not None:
                conn.execute(tb.campaigns.update().where(tb.campaigns.c.id == campaign)
                             .values(plan=dumps(plan)))
            touch(conn, campaign, time.time())

        self._write("save the plan", body)

    def record_measurement(self, campaign: str, index: int, role: str, q: Sequence[float],
                           p: Sequence[float], *, q_spread: Sequence[float] | None = None,
                           p_spread: Sequence[float] | None = None, samples: int = 1,
                           deviation: float | None = None, t: float | None = None,
                           tracker_samples: Sequence[Sequence[float]] | None = None,
                           joint_samples: Sequence[Sequence[float]] | None = None) -> int:
        """Record one measured point and return its id; committed (and synced) before returning.

        The pose is marked measured (and created if it was not planned). Raw tracker points
        (n×3) and joint readings (n×6), when given, are kept with it. Recording the same
        (campaign, index, t) again stores nothing and returns the existing id.
        """
        when = time.time() if t is None else t
        return self._write(f"record the measurement of pose {index}", lambda conn: insert_measurement(
            conn, campaign, index, role, q, p, q_spread, p_spread, samples, deviation, when,
            tracker_samples, joint_samples, self.location))

    def record_skip(self, campaign: str, index: int, role: str, reason: str) -> None:
        """Mark a pose skipped (unreachable, no line of sight...), so a resume does not retry it."""
        now = time.time()
        self._write(f"record the skip of pose {index}",
                    lambda conn: skip_pose(conn, campaign, index, role, reason, now, self.location))

    # --- models and validation ----------------------------------------------------------------
    def save_model(self, campaign: str, doc: Mapping[str, Any]) -> int:
        """Keep a ``hil-model/1`` document; returns its id (the same id for the same document)."""
        now = time.time()
        return self._write("save the model",
                           lambda conn: insert_model(conn, campaign, doc, now, self.location))

    def save_validation(self, campaign: str, before: Mapping[str, Any], after: Mapping[str, Any],
                        passed: bool, *, model: int | None = None,
                        details: Mapping[str, Any] | None = None) -> int:
        """Keep a validation result (error stats of the nominal and the calibrated model on
        held-out poses: count, mean, rms, max; `details` for ISO 9283 AP/RP and the like).
        `model` defaults to the campaign's latest model. Returns its id (same result, same id)."""
        now = time.time()
        return self._write("save the validation", lambda conn: insert_validation(
            conn, campaign, before, after, passed, model, details, now, self.location))
