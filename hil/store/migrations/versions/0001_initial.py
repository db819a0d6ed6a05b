"""v1: stations, robots, campaigns, poses, measurements, samples, models, validations, events.

Revision ID: 0001
Revises:
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0001"
down_revision = None
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "stations",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("name", sa.Text, nullable=False, unique=True),
        sa.Column("created", sa.Float, nullable=False))
    op.create_table(
        "robots",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("serial", sa.Text, nullable=False, unique=True),
        sa.Column("type", sa.Text, nullable=False),
        sa.Column("model", sa.Text, nullable=False, server_default=""),
        sa.Column("software", sa.Text, nullable=False, server_default=""),
        sa.Column("first_seen", sa.Float, nullable=False),
        sa.Column("last_seen", sa.Float, nullable=False))
    op.create_table(
        "campaigns",
        sa.Column("id", sa.Text, primary_key=True),
        sa.Column("station", sa.Integer, sa.ForeignKey("stations.id"), nullable=False),
        sa.Column("robot", sa.Integer, sa.ForeignKey("robots.id")),
        sa.Column("robot_type", sa.Text, nullable=False),
        sa.Column("config", sa.Text, nullable=False),
        sa.Column("plan", sa.Text),
        sa.Column("status", sa.Text, nullable=False),
        sa.Column("detail", sa.Text, nullable=False, server_default=""),
        sa.Column("result", sa.Text),
        sa.Column("software", sa.Text, nullable=False, server_default=""),
        sa.Column("created", sa.Float, nullable=False),
        sa.Column("updated", sa.Float, nullable=False))
    op.create_index("campaigns_created", "campaigns", ["created"])
    op.create_table(
        "poses",
        sa.Column("campaign", sa.Text, sa.ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
        sa.Column("idx", sa.Integer, nullable=False),
        sa.Column("role", sa.Text, nullable=False),
        sa.Column("target", sa.Text, nullable=False),
        sa.Column("status", sa.Text, nullable=False, server_default="planned"),
        sa.Column("reason", sa.Text, nullable=False, server_default=""),
        sa.PrimaryKeyConstraint("campaign", "idx"),
        sa.CheckConstraint("role IN ('bootstrap', 'calibration', 'validation')", name="poses_role"),
        sa.CheckConstraint("status IN ('planned', 'measured', 'skipped')", name="poses_status"))
    op.create_table(
        "measurements",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("campaign", sa.Text, sa.ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
        sa.Column("pose", sa.Integer, nullable=False),
        sa.Column("role", sa.Text, nullable=False),
        sa.Column("q", sa.Text, nullable=False),
        sa.Column("q_spread", sa.Text),
        sa.Column("p", sa.Text, nullable=False),
        sa.Column("p_spread", sa.Text),
        sa.Column("samples", sa.Integer, nullable=False),
        sa.Column("deviation", sa.Float),
        sa.Column("t", sa.Float, nullable=False),
        sa.UniqueConstraint("campaign", "pose", "t"))
    op.create_table(
        "samples",
        sa.Column("measurement", sa.Integer, sa.ForeignKey("measurements.id", ondelete="CASCADE"),
                  nullable=False),
        sa.Column("kind", sa.Text, nullable=False),
        sa.Column("k", sa.Integer, nullable=False),
        sa.Column("value", sa.Text, nullable=False),
        sa.PrimaryKeyConstraint("measurement", "kind", "k"),
        sa.CheckConstraint("kind IN ('tracker', 'joints')", name="samples_kind"))
    op.create_table(
        "models",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("campaign", sa.Text, sa.ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
        sa.Column("doc", sa.Text, nullable=False),
        sa.Column("sha256", sa.Text, nullable=False),
        sa.Column("rms", sa.Float),
        sa.Column("created", sa.Float, nullable=False),
        sa.UniqueConstraint("campaign", "sha256"))
    op.create_table(
        "validations",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("campaign", sa.Text, sa.ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
        sa.Column("model", sa.Integer, sa.ForeignKey("models.id")),
        sa.Column("before", sa.Text, nullable=False),
        sa.Column("after", sa.Text, nullable=False),
        sa.Column("passed", sa.Integer, nullable=False),
        sa.Column("rms", sa.Float),
        sa.Column("details", sa.Text),
        sa.Column("sha256", sa.Text, nullable=False),
        sa.Column("created", sa.Float, nullable=False),
        sa.UniqueConstraint("campaign", "sha256"))
    op.create_table(
        "events",
        sa.Column("campaign", sa.Text, sa.ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
        sa.Column("seq", sa.Integer, nullable=False),
        sa.Column("t", sa.Float, nullable=False),
        sa.Column("type", sa.Text, nullable=False),
        sa.Column("data", sa.Text, nullable=False),
        sa.PrimaryKeyConstraint("campaign", "seq"))
