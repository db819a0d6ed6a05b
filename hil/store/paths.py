"""Where the database lives when nobody says.

A store is an SQLite file or a PostgreSQL database (``postgresql://user@host/db``). Precedence, most
specific first: an explicit location (``--db``), the ``HIL_DB`` environment variable, the station
config's ``store.url`` (or its older spelling ``store.path``; relative file paths are taken from the
config file's directory, so a station folder can carry its own database), then
``$XDG_DATA_HOME/hil/hil.db`` or ``~/.local/share/hil/hil.db``. The environment beats the config
file so a test cell or a CI job can redirect every command without editing station files.

A simulated station (``--sim``) is not the plant's: its campaigns go to a store of their own,
``sim.db`` beside the per-user default (`simulated_path`), unless ``--db`` names one. ``HIL_DB`` —
often the plant's PostgreSQL — is not used for them, so a simulated robot never shows up in ``hil
robots`` or the fleet report by accident; ``--db`` is how to ask for it (`resolve_location` with
``simulated=True``).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ENV_VAR = "HIL_DB"
#: the file of the simulated stations' store, beside the per-user default
SIMULATED_FILE = "sim.db"

#: URL schemes that name a PostgreSQL server (the ``+driver`` forms SQLAlchemy users write included).
POSTGRES_SCHEMES = ("postgresql", "postgres", "postgresql+psycopg")


def is_url(text: str | os.PathLike[str]) -> bool:
    """True for a database URL (``postgresql://…``, ``sqlite:///…``), False for a file path."""
    scheme = str(text).split("://", 1)[0] if "://" in str(text) else ""
    return scheme.lower() in (*POSTGRES_SCHEMES, "sqlite")


def is_postgres(text: str | os.PathLike[str]) -> bool:
    return is_url(text) and str(text).split("://", 1)[0].lower() in POSTGRES_SCHEMES




def default_path(env: Mapping[str, str] | None = None) -> Path:
    """The per-user default: ``$XDG_DATA_HOME/hil/hil.db``, else ``~/.local/share/hil/hil.db``.

    Per the XDG base-directory spec, a relative ``XDG_DATA_HOME`` is invalid and ignored.
    """
    env = os.environ if env is None else env
    base = env.get("XDG_DATA_HOME", "")
    root = Path(base) if base and os.path.isabs(base) else Path.home() / ".local" / "share"
    return root / "hil" / "hil.db"


def simulated_path(env: Mapping[str, str] | None = None) -> Path:
    """The simulated stations' store: ``sim.db`` beside the per-user default (`default_path`)."""
    return default_path(env).with_name(SIMULATED_FILE)


def _plain(text: str, field: str = "--db") -> str | Path:
    """A location as given: a PostgreSQL URL stays text, ``sqlite:///f.db`` and a path become a Path.
    Another database's URL, a server URL without a host and a URL with a typo (``dbhost:5432/hil``) are
    bad input naming `field`: taken for a path, they would become folders or "no such database"."""
    from hil.errors import InputError
    from hil.station.store_url import store_url_problem

    if "://" in text and not is_postgres(text) and not text.startswith("sqlite:///"):
        raise InputError(f"{field}: {text.split('://', 1)[0]}:// is not a store; give a file path or a "
                         "postgresql:// URL")
    problem = store_url_problem(text)
    if problem is not None:
        raise InputError(f"{field}: {problem}")
    if is_postgres(text):
        return text
    if text.startswith("sqlite:///"):
        text = text[len("sqlite:///"):]  # sqlite:////abs/path keeps its leading slash
    return Path(text).expanduser()


@dataclass(frozen=True)
class Located:
    """A store's location and where it was given, so that an error names what the user typed."""

    #: a Path (SQLite file) or a ``postgresql://`` URL
    location: str | Path
    #: how an error names it: ``--db``, ``$HIL_DB``, ``station.toml: store.url``, ``the default store``…
    field: str
    #: given by the user (``--db``, ``$HIL_DB``, the config), not a default whose folders hil makes
    explicit: bool


def _config_store_location(config: Any) -> tuple[str | Path, str] | None:
    """(``store.url`` or ``store.path`` of a StationConfig or its dict, the key with its file); a
    relative file path is resolved against the config file's folder."""
    if config is None:
        return None
    if hasattr(config, "as_dict"):
        values, source = config.as_dict(), getattr(config, "source", "")
    else:
        values, source = config, ""
    store = values.get("store") or {}
    key = "store.url" if store.get("url") else "store.path"
    text = store.get("url") or store.get("path") or ""
    if not text:
        return None
    field = f"{source}: {key}" if source and not source.startswith("<") else key
    location = _plain(str(text), field)
    if (isinstance(location, Path) and not location.is_absolute() and source
            and not source.startswith("<") and os.path.exists(source)):
        location = Path(source).resolve().parent / location
    return location, field


def locate(path: str | os.PathLike[str] | None = None, config: Any = None,
           env: Mapping[str, str] | None = None, *, simulated: bool = False) -> Located:
    """The store to use and where it was said (see the module docstring for the precedence).
    `simulated`: for a simulated station's campaigns: `path`, else `simulated_path`."""
    env = os.environ if env is None else env
    if path is not None and str(path) != "":
        return Located(_plain(str(path)), "--db", True)
    if simulated:
        return Located(simulated_path(env), "the simulated stations' store", False)
    if env.get(ENV_VAR):
        return Located(_plain(env[ENV_VAR], f"${ENV_VAR}"), f"${ENV_VAR}", True)
    configured = _config_store_location(config)
    if configured is not None:
        return Located(*configured, True)
    return Located(default_path(env), "the default store", False)


def resolve_location(path: str | os.PathLike[str] | None = None, config: Any = None,
                     env: Mapping[str, str] | None = None, *, simulated: bool = False) -> str | Path:
    """The store to use: a Path (SQLite file) or a ``postgresql://`` URL (see the module docstring).
    `simulated`: for a simulated station's campaigns: `path`, else `simulated_path`."""
    return locate(path, config, env, simulated=simulated).location


def check_store(located: Located, *, create: bool) -> None:
    """InputError naming `located.field` for an SQLite store that cannot be used, before anything
    connects: with `create` False (a command that only reads) a file that does not exist, saying
    whether its folder is missing too; with `create`, a file that cannot be created (`check_creatable`)
    or, for a location the user gave, one whose folder does not exist — a typo or an unmounted share
    would otherwise get a fresh, empty store of its own. The defaults' folders are made as needed."""
    from hil.errors import InputError

    path = located.location
    if not isinstance(path, Path):
        return
    if path.exists():
        import stat

        from hil.files.inputs import file_kind

        mode = path.stat().st_mode
        if stat.S_ISDIR(mode):
            raise InputError(f"{located.field}: {path} is a folder, not a database file")
        if not stat.S_ISREG(mode):  # SQLite would block on a FIFO or read /dev/zero for ever
            raise InputError(f"{located.field}: {path} is {file_kind(mode)}, not a database file")
        return
    folder = path.parent
    if not create:
        missing = "" if folder.is_dir() else f" (nor its folder {folder})"
        raise InputError(f"{located.field}: {path}: no such database{missing}")
    if located.explicit and not folder.exists():
        raise InputError(f"{located.field}: {path}: its folder {folder} does not exist; make it, or name "
                         "another store")
    check_creatable(path, located.field)


def resolve_path(path: str | os.PathLike[str] | None = None, config: Any = None,
                 env: Mapping[str, str] | None = None) -> str | Path:
    """Alias of `resolve_location` (a Path for an SQLite file, a URL string for PostgreSQL)."""
    return resolve_location(path, config, env)


def check_creatable(path: Path, field: str) -> None:
    """InputError naming `field` when no database file can be created at `path` (a folder under
    ``/proc``, a file where a folder should be, a read-only place): found with the rest of the config,
    before any connection, rather than after the arm was reached. The nearest existing
    folder is probed with a temporary file, removed at once: permission bits do not show a pseudo or
    read-only file system, and root passes every access() test."""
    import tempfile

    from hil.errors import InputError

    folder = path.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        raise InputError(f"{field}: cannot create the store {path}: {folder} is not a folder")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise InputError(f"{field}: cannot create the store {path}: {folder}: "
                         f"{exc.strerror or exc}") from None
