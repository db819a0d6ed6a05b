"""The durable store: every campaign, pose, measurement, model, validation and event, in SQLite.

"The store is the truth" (DESIGN.md): each measurement is committed before the next move, a killed
run resumes from what is here, and ``hil history`` / ``hil show`` read it. See `hil.store.core` for
the durability and threading rules, `hil.store.schema` for the tables and their upgrade steps, and
`hil.store.paths` for where the file lives, `hil.store.leases` for who may run a campaign and drive
an arm.

May import: `hil.campaign.events` (what it records), `hil.errors`. Never the CLI or the TUI.
"""

from hil.store.core import Store, StoreError, UnknownCampaignError, new_campaign_id
from hil.store.leases import Lease, LeaseRefused, address_lock
from hil.store.paths import ENV_VAR, default_path, resolve_path
from hil.store.records import (
    FINISHED,
    INTERRUPTED,
    ROLES,
    CampaignRecord,
    CampaignSummary,
    Measurement,
    ModelRecord,
    PlannedPose,
    RobotInfo,
    ValidationRecord,
)
from hil.store.schema import SCHEMA_VERSION, config_hash, measurement_hash

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
    "Measurement",
    "ModelRecord",
    "PlannedPose",
    "RobotInfo",
    "Store",
    "StoreError",
    "UnknownCampaignError",
    "ValidationRecord",
    "address_lock",
    "config_hash",
    "default_path",
    "measurement_hash",
    "new_campaign_id",
    "resolve_path",
]
