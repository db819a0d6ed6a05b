"""The campaign database every output path is checked against (`hil.files.outputs.check_output`).

Commands that never open the store (identify, fk, export, ...) still must not write over it: ``hil
identify --out "$HIL_DB"`` would replace every campaign with a model file. So each command checks its
outputs against the database it would use — ``--db``, else ``$HIL_DB``, else the config's
``store.url``/``store.path``, else the user's default (`hil.store.resolve_location`) — named the way
the user gave it. A PostgreSQL store is no file an output could overwrite: then there is none to check.
"""

from __future__ import annotations

import os
from pathlib import Path

from hil.store.paths import ENV_VAR, resolve_location


def _file(location: str | Path) -> Path | None:
    return location if isinstance(location, Path) else None


def campaign_store(db: str | None = None, config_path: str | None = None, *,
                   sim: bool = False) -> tuple[Path | None, str]:
    """(database file or None for a server, how an error names it) for ``--db`` `db` and ``--config``
    `config_path`; `sim`: of a simulated station's job, whose campaigns go to the simulated stations'
    store (`hil.store.paths.simulated_path`) unless ``--db`` names one.

    The config is read only when it decides (no ``--db``, no ``$HIL_DB``): a bad one is then an
    InputError naming it, as the command would give anyway.
    """
    if db:
        return _file(resolve_location(db)), "--db"
    if sim:
        return _file(resolve_location(None, simulated=True)), "the simulated stations' store"
    if os.environ.get(ENV_VAR):
        return _file(resolve_location(None)), f"${ENV_VAR}"
    config = None
    if config_path:
        from hil.station.config import load_config

        config = load_config(config_path)
    store = config.as_dict().get("store", {}) if config is not None else {}
    where = ("store.url of --config" if store.get("url") else "store.path of --config" if store.get("path")
             else "the campaign database")
    return _file(resolve_location(None, config)), where
