"""v3: leases (one process per campaign, one campaign per robot: `hil.store.leases`) and a measurement
hash on campaigns (filled in for existing ones), which resume matches instead of the config hash, so a
changed tracker URL or timeout no longer orphans an unfinished campaign.

Revision ID: 0003
Revises: 0002
"""

from __future__ import annotations

import json

import sqlalchemy as sa
from alembic import op

from hil.store.hashing import measurement_hash

revision = "0003"
down_revision = "0002"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "leases",
        sa.Column("name", sa.Text, primary_key=True),
        sa.Column("campaign", sa.Text, nullable=False),
        sa.Column("owner", sa.Text, nullable=False),
        sa.Column("token", sa.Text, nullable=False),
        sa.Column("since", sa.Float, nullable=False),
        sa.Column("heartbeat", sa.Float, nullable=False))
    op.create_index("leases_token", "leases", ["token"])
    op.add_column("campaigns", sa.Column("measure_hash", sa.Text, nullable=False, server_default=""))
    campaigns = sa.table("campaigns", sa.column("id"), sa.column("config"), sa.column("measure_hash"))
    conn = op.get_bind()
    for cid, config in conn.execute(sa.select(campaigns.c.id, campaigns.c.config)).all():
        conn.execute(campaigns.update().where(campaigns.c.id == cid)
                     .values(measure_hash=measurement_hash(json.loads(config))))
    op.create_index("campaigns_measure", "campaigns", ["measure_hash", "created"])
