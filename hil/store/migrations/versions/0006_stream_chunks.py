"""v6: a sweep's two streams, in chunks committed as they are recorded.

A sweep campaign (``campaign.mode = "sweep"``) records the controller's joints (RTDE ``timestamp`` and
``actual_q``) and the tracker's continuous points (emScon's own stamps) while the arm moves. Each
stream arrives in chunks of a few hundred samples, one row per chunk (`hil.store.tables.stream_chunks`
says why the columns are what they are); a segment's rows count only once its ``SweepSegmentDone``
event names their ``take``.

Revision ID: 0006
Revises: 0005
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0006"
down_revision = "0005"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "stream_chunks",
        sa.Column("campaign", sa.Text, sa.ForeignKey("campaigns.id", ondelete="CASCADE"), nullable=False),
        sa.Column("segment", sa.Integer, nullable=False),
        sa.Column("take", sa.Text, nullable=False),
        sa.Column("stream", sa.Text, nullable=False),
        sa.Column("chunk", sa.Integer, nullable=False),
        sa.Column("session", sa.Text, nullable=False, server_default=""),
        sa.Column("count", sa.Integer, nullable=False),
        sa.Column("t0", sa.Float, nullable=False),
        sa.Column("t1", sa.Float, nullable=False),
        sa.Column("data", sa.Text, nullable=False),
        sa.PrimaryKeyConstraint("campaign", "segment", "take", "stream", "chunk"))
