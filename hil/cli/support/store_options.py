"""The store options the fleet commands share (``hil robots``, ``hil robot``, ``hil fleet-report``):
``--db`` (a file or a ``postgresql://`` URL), ``--config`` (its ``store.url`` / ``store.path``),
``--json``, and opening the store without ever creating one.
"""

from __future__ import annotations

import argparse
import os
import time
from typing import TYPE_CHECKING

from hil.cli.support.options import TOML_FILE

if TYPE_CHECKING:
    from hil.store import Store
    from hil.store.sqlite_reader import SqliteReader

DB_HELP = ("the store: an SQLite file path or a postgresql:// URL (default: $HIL_DB, the config's "
           "store.url or store.path, or the user's data directory)")


def add_store_options(p: argparse.ArgumentParser, *, json: bool = True) -> None:
    p.add_argument("--db", metavar="LOCATION", help=DB_HELP)
    p.add_argument("--config", metavar="station.toml", type=TOML_FILE,
                   help="take the store's location from it")
    if json:
        p.add_argument("--json", action="store_true", help="print JSON on stdout")


def open_store(args: argparse.Namespace, *, readonly: bool = True) -> Store | SqliteReader:
    """The store `args` name, opened read-only unless asked; a missing one is bad input (exit 2): a
    command that reads (or marks) never creates a database. Read-only, a station's SQLite file at this
    hil's schema is read through sqlite3 alone (`hil.store.sqlite_reader`: no SQLAlchemy to import,
    the same SQL and answers); anything else opens the `Store`."""
    config = None
    if args.config:  # the station's configuration is read only when it names the store
        from hil.station.config import load_config

        config = load_config(args.config)
    return open_location(args.db or None, config, readonly=readonly)


def open_location(db: str | None, config: object = None, *, readonly: bool = True) -> Store | SqliteReader:
    """`open_store` of a ``--db`` value (None: the environment's or the config's store)."""
    if readonly:
        from hil.store.paths import resolve_location
        from hil.store.sqlite_reader import open_reader

        reader = open_reader(resolve_location(db, config))
        if reader is not None:
            return reader
    from hil.store import Store

    return Store.open(db, config=config, readonly=readonly, create=False)


def where(store: Store) -> str:
    """The store as the ``database:`` line on stderr names it: an absolute path, or the URL without
    its password."""
    path = getattr(store, "path", None)
    return os.path.abspath(path) if path is not None else store.location


def when(t: float | None, fmt: str = "%Y-%m-%d") -> str:
    """Local time of an epoch time, "-" when unknown."""
    return "-" if t is None else time.strftime(fmt, time.localtime(t))


def mm(value: float | None, digits: int = 3) -> str:
    """Metres as millimetres without the unit, "-" when unknown."""
    return "-" if value is None else f"{value * 1e3:.{digits}f}"


def clip(text: str, width: int) -> str:
    """`text` cut to `width` characters, an ellipsis marking the cut."""
    return text if len(text) <= width else text[: width - 1] + "…"
