"""v5: each campaign keeps the controller's own kinematic model it ran with, and says what it is.

``robots.controller`` (v4) holds the latest KinematicsInfo a robot's controller reported; a campaign
needs the one *it* ran with, since a controller can be recalibrated (or its calibration.conf
replaced) between two campaigns, and the comparison and export of a campaign must use the model the
arm moved with then. NULL for campaigns of an older hil and for controllers that did not say.

``campaigns.kind``: ``calibration`` (every campaign of an older hil) or ``verification`` (an ISO 9283
pose test, ``hil verify``): a verification has no model, and a robot's calibration history, its current
model and the fleet's "last calibration" must not take one for a failed calibration.

Revision ID: 0005
Revises: 0004
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0005"
down_revision = "0004"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.add_column("campaigns", sa.Column("controller", sa.Text))
    op.add_column("campaigns", sa.Column("kind", sa.Text, nullable=False, server_default="calibration"))
