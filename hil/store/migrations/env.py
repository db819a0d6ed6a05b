"""Alembic's environment for the hil store.

hil runs the migrations itself (`hil.store.migrate.upgrade`), on a connection it has already opened
inside its write transaction, so the upgrade is one transaction and a crash mid-upgrade leaves the old
version intact. This file also lets a developer run ``alembic`` by hand (``-x url=…``) to write a new
revision. Revisions are hand-written, append-only, and must run on SQLite and PostgreSQL alike.
"""

from __future__ import annotations

from alembic import context
from sqlalchemy import create_engine

from hil.store.tables import metadata

connection = context.config.attributes.get("connection")
if connection is not None:
    context.configure(connection=connection, target_metadata=metadata, transaction_per_migration=False)
    with context.begin_transaction():
        context.run_migrations()
else:  # a developer's ``alembic -x url=sqlite:///x.db upgrade head``
    url = context.get_x_argument(as_dictionary=True).get("url", "sqlite:///hil-dev.db")
    with create_engine(url).begin() as conn:
        context.configure(connection=conn, target_metadata=metadata)
        with context.begin_transaction():
            context.run_migrations()
