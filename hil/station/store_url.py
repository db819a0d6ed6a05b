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
        host = rest.split("/", 1)[0].split("@")[-1]
        if not host:
            return "a postgresql:// URL needs a host: postgresql://user@host[:port]/database"
        return _port_problem(host)
    if scheme == "sqlite":
        return None if v.startswith("sqlite:///") else "an SQLite URL is sqlite:///path/to/file.db"
    return f"must be a file path or a postgresql:// URL, got a {scheme}:// URL"


def _port_problem(host: str) -> str | None:
    """What is wrong with the port of `host` ("name", "name:port", "[v6]:port"), None if nothing: a TCP
    port is a whole number 1..65535; 0 or 99999 would only fail as "cannot connect" (a hardware fault,
    exit 3) after the connection was tried."""
    port = host.rsplit("]", 1)[-1].rpartition(":")[2] if ":" in host.rsplit("]", 1)[-1] else None
    if port is None:
        return None
    if not port.isdigit() or not 1 <= int(port) <= 65535:
        return f"port {port!r} of a postgresql:// URL is not a TCP port: a whole number from 1 to 65535"
    return None
