"""Alembic migrations of the hil store (see `hil.store.migrate`)."""
