"""A store's location names where it was given (--db, $HIL_DB, the config's key, the default), and one
that cannot be used is said so in one line naming it, before anything connects (issue 31)."""

from __future__ import annotations

from pathlib import Path

import pytest

from hil.errors import InputError
from hil.station.config import load_config
from hil.store.paths import Located, check_store, locate


def _config(tmp_path: Path, url: str) -> object:
    station = tmp_path / "station.toml"
    station.write_text(f'[store]\nurl = "{url}"\n')
    return load_config(station)


def test_each_location_is_named_as_it_was_given(tmp_path: Path) -> None:
    config = _config(tmp_path, "cell.db")
    assert locate("a.db", config, {"HIL_DB": "/env.db"}) == Located(Path("a.db"), "--db", True)
    assert locate(None, config, {"HIL_DB": "/env.db"}) == Located(Path("/env.db"), "$HIL_DB", True)
    located = locate(None, config, {"XDG_DATA_HOME": str(tmp_path)})
    assert located.location == tmp_path / "cell.db" and located.explicit
    assert located.field == f"{tmp_path / 'station.toml'}: store.url"
    default = locate(None, None, {"XDG_DATA_HOME": str(tmp_path)})
    assert default == Located(tmp_path / "hil" / "hil.db", "the default store", False)


@pytest.mark.parametrize(("text", "says"), [
    ("dbhost:5432/hil", "is not a URL"), ("postgresql:/hil", "is not a URL"),
    ("postgresql:///hil", "needs a host"), ("mysql://h/db", "mysql:// is not a store"),
])
def test_a_location_that_is_not_one_is_refused_naming_its_option(text: str, says: str) -> None:
    with pytest.raises(InputError, match=f"^--db: .*{says}"):
        locate(text, None, {})
    with pytest.raises(InputError, match=rf"^\$HIL_DB: .*{says}"):
        locate(None, None, {"HIL_DB": text})


def test_a_reader_is_told_the_file_is_missing_and_whether_its_folder_is(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"^--db: .*gone\.db: no such database$"):
        check_store(Located(tmp_path / "gone.db", "--db", True), create=False)
    with pytest.raises(InputError, match=r"^s\.toml: store\.url: .*database \(nor its folder .*nope\)$"):
        check_store(Located(tmp_path / "nope" / "x.db", "s.toml: store.url", True), create=False)
    check_store(Located("postgresql://u@h/d", "--db", True), create=False)  # a server is asked later


def test_a_writer_makes_no_folder_the_user_named_but_makes_the_defaults(tmp_path: Path) -> None:
    """A typo, or a share not mounted, would get a fresh empty store of its own in a new folder."""
    with pytest.raises(InputError, match=r"^\$HIL_DB: .*its folder .*nope does not exist"):
        check_store(Located(tmp_path / "nope" / "x.db", "$HIL_DB", True), create=True)
    check_store(Located(tmp_path / "x.db", "--db", True), create=True)  # the folder exists: created later
    check_store(Located(tmp_path / "data" / "hil" / "hil.db", "the default store", False), create=True)
    assert not (tmp_path / "nope").exists() and not (tmp_path / "data").exists()
