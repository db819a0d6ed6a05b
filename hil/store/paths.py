"""Where the database lives when nobody says.

Precedence, most specific first: an explicit path (``--db``), the ``HIL_DB`` environment variable,
the station config's ``store.path`` (relative paths are taken from the config file's directory, so a
station folder can carry its own database), then ``$XDG_DATA_HOME/hil/hil.db`` or
``~/.local/share/hil/hil.db``. The environment beats the config file so a test cell or a CI job can
redirect every command without editing station files.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

ENV_VAR = "HIL_DB"


def default_path(env: Mapping[str, str] | None = None) -> Path:
    """The per-user default: ``$XDG_DATA_HOME/hil/hil.db``, else ``~/.local/share/hil/hil.db``.

    Per the XDG base-directory spec, a relative ``XDG_DATA_HOME`` is invalid and ignored.
    """
    env = os.environ if env is None else env
    base = env.get("XDG_DATA_HOME", "")
    root = Path(base) if base and os.path.isabs(base) else Path.home() / ".local" / "share"
    return root / "hil" / "hil.db"


def _config_store_path(config: Any) -> Path | None:
    """``store.path`` of a StationConfig (or its dict), resolved against the config file's folder."""
    if config is None:
        return None
    if hasattr(config, "as_dict"):
        values, source = config.as_dict(), getattr(config, "source", "")
    else:
        values, source = config, ""
    text = (values.get("store") or {}).get("path") or ""
    if not text:
        return None
    path = Path(text).expanduser()
    if not path.is_absolute() and source and not source.startswith("<") and os.path.exists(source):
        path = Path(source).resolve().parent / path
    return path


def resolve_path(path: str | os.PathLike[str] | None = None, config: Any = None,
                 env: Mapping[str, str] | None = None) -> Path:
    """The database file to use (see the module docstring for the precedence)."""
    env = os.environ if env is None else env
    if path is not None and str(path) != "":
        return Path(path).expanduser()
    if env.get(ENV_VAR):
        return Path(env[ENV_VAR]).expanduser()
    return _config_store_path(config) or default_path(env)
