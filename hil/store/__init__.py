"""The durable store: every campaign, pose, measurement, model, validation and event, in SQLite (one
station) or PostgreSQL (a plant's fleet), through SQLAlchemy Core with Alembic migrations.

"The store is the truth" (docs/design.md, The store): each measurement is committed before the next
move, a killed
run resumes from what is here, and ``hil history`` / ``hil show`` read it. `Store`
(`hil.store.core`) is the one object callers get; it is made of `hil.store.transactions` (the
durability, threading and lost-link rules), `hil.store.queries` (the read side),
`hil.store.recorder` (campaign events into rows) and `hil.store.rows` (the rows a write adds). See
`hil.store.database` for the SQLite and PostgreSQL engines, `hil.store.tables` for the tables,
`hil.store.migrate` for their upgrades, `hil.store.paths` for where the store lives,
`hil.store.leases` for who may run a campaign and drive an arm, `hil.store.fleet` for a plant's
robots and their calibration history.

May import: `hil.campaign.events` (what it records), `hil.campaign.ids` (a campaign's id),
`hil.errors`. Never the CLI or the TUI.
"""

from typing import TYPE_CHECKING

from hil.store.paths import (
    ENV_VAR,
    Located,
    check_store,
    default_path,
    is_postgres,
    locate,
    resolve_location,
    resolve_path,
    simulated_path,
)

if TYPE_CHECKING:
    from hil.campaign.ids import new_campaign_id
    from hil.store.core import Store, StoreError, UnknownCampaignError
    from hil.store.hashing import config_hash, measurement_hash
    from hil.store.leases import Lease, LeaseRefused, address_lock
    from hil.store.migrate import SCHEMA_VERSION
    from hil.store.records import (
        FINISHED,
        INTERRUPTED,
        ROLES,
        CampaignRecord,
        CampaignSummary,
        Measurement,
        ModelRecord,
        PlannedPose,
        RobotIdentity,
        ValidationRecord,
    )

#: The names beyond where the store lives, by the module that defines them, imported when first asked
#: for: a command that only asks where the store is (every output path is checked against it) does not
#: import SQLAlchemy (bench/cli_startup.py).
_LAZY = {
    "new_campaign_id": "hil.campaign.ids",
    "Store": "hil.store.core", "StoreError": "hil.store.core", "UnknownCampaignError": "hil.store.core",
    "config_hash": "hil.store.hashing", "measurement_hash": "hil.store.hashing",
    "Lease": "hil.store.leases", "LeaseRefused": "hil.store.leases", "address_lock": "hil.store.leases",
    "SCHEMA_VERSION": "hil.store.migrate",
    **{name: "hil.store.records" for name in (
        "FINISHED", "INTERRUPTED", "ROLES", "CampaignRecord", "CampaignSummary", "Measurement",
        "ModelRecord", "PlannedPose", "RobotIdentity", "ValidationRecord")},
}


def __getattr__(name: str) -> object:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


__all__ = [
    "ENV_VAR",
    "FINISHED",
    "INTERRUPTED",
    "ROLES",
    "SCHEMA_VERSION",
    "CampaignRecord",
    "CampaignSummary",
    "Lease",
    "LeaseRefused",
    "Located",
    "Measurement",
    "ModelRecord",
    "PlannedPose",
    "RobotIdentity",
    "Store",
    "StoreError",
    "UnknownCampaignError",
    "ValidationRecord",
    "address_lock",
    "check_store",
    "config_hash",
    "default_path",
    "is_postgres",
    "locate",
    "measurement_hash",
    "new_campaign_id",
    "resolve_location",
    "resolve_path",
    "simulated_path",
]
