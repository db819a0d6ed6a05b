"""v4, the fleet: a robot's factory calibration, marks on calibrations, per-robot history index, and
an id per recorded event so a write retried after a lost database link is not recorded twice.

Revision ID: 0004
Revises: 0003
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0004"
down_revision = "0003"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.add_column("robots", sa.Column("controller", sa.Text))
    op.add_column("events", sa.Column("uid", sa.Text))
    op.create_index("events_uid", "events", ["uid"], unique=True)
    op.create_index("campaigns_robot", "campaigns", ["robot", "created"])
    op.create_table(
        "marks",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("campaign", sa.Text, sa.ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
        sa.Column("bad", sa.Integer, nullable=False),
        sa.Column("reason", sa.Text, nullable=False),
        sa.Column("who", sa.Text, nullable=False, server_default=""),
        sa.Column("t", sa.Float, nullable=False))
    op.create_index("marks_campaign", "marks", ["campaign", "id"])
