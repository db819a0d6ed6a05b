"""What a store's location may be, as text: one rule for the config's ``store.url``, ``--db`` and
``$HIL_DB`` (`hil.store.paths` applies it to the last two, `hil.station.config` to the first).

It sits in the station layer, below the store, and imports nothing, so a listing command that reads
no config pays nothing for it.
"""

from __future__ import annotations

import re


def store_url_problem(v: str) -> str | None:
    """What is wrong with `v` as a store's location, None if nothing: a store is an SQLite file (a path,
    or ``sqlite:///path``) or a PostgreSQL database (``postgresql://user@host:port/db``); another
    database's URL would fail only when the run starts, and a URL with a typo would be taken for a file
    path ("no such database")."""
    if "://" not in v:
        head = v.split("/", 1)[0]
        if ":" in head and not re.fullmatch(r"[A-Za-z]:", head):  # "postgresql:/db", "dbhost:5432/hil"
            return (f"{v!r} is not a URL (scheme://host/database) and not a file path either: a URL is "
                    "postgresql://user@host[:port]/database, a file a path without ':'")
        return None
    scheme = v.split("://", 1)[0].lower()
    if scheme in ("postgresql", "postgres", "postgresql+psycopg"):
        rest = v.split("://", 1)[1]
        host = rest.split("@")[-1].split("/", 1)[0]
        return None if host else "a postgresql:// URL needs a host: postgresql://user@host[:port]/database"
    if scheme == "sqlite":
        return None if v.startswith("sqlite:///") else "an SQLite URL is sqlite:///path/to/file.db"
    return f"must be a file path or a postgresql:// URL, got a {scheme}:// URL"
