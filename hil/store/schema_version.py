"""The schema revision this code reads and writes, as a constant that imports nothing.

`hil.store.migrate` upgrades a store to it with Alembic; `hil.store.sqlite_reader` checks a file is at
it before reading it with Python's own sqlite3 (a listing then loads neither Alembic nor SQLAlchemy).
tests/hil/store/test_sqlite_reader.py checks it equals the migrations' head.
"""

from __future__ import annotations

#: The newest revision this code knows (the head of `hil.store.migrations`).
HEAD = "0006"
#: The schema version a number can say: revision "000N" is version N.
SCHEMA_VERSION = int(HEAD)
