"""v2: a config hash on campaigns (filled in for existing ones) and the indexes resume needs.

Revision ID: 0002
Revises: 0001
"""

from __future__ import annotations

import json

import sqlalchemy as sa
from alembic import op

from hil.store.hashing import config_hash

revision = "0002"
down_revision = "0001"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.add_column("campaigns", sa.Column("config_hash", sa.Text, nullable=False, server_default=""))
    campaigns = sa.table("campaigns", sa.column("id"), sa.column("config"), sa.column("config_hash"))
    conn = op.get_bind()
    for cid, config in conn.execute(sa.select(campaigns.c.id, campaigns.c.config)).all():
        conn.execute(campaigns.update().where(campaigns.c.id == cid)
                     .values(config_hash=config_hash(json.loads(config))))
    op.create_index("campaigns_resume", "campaigns", ["config_hash", "created"])
    op.create_index("events_type", "events", ["campaign", "type"])
