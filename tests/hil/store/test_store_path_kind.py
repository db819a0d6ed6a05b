"""A store location that exists but is not a regular file is refused naming its key, before SQLite
opens it: SQLite blocked on a FIFO and took a character device for an empty database (issue 31)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from hil.errors import InputError
from hil.store.paths import check_store, locate


@pytest.mark.parametrize("create", [False, True], ids=["reading", "writing"])
def test_a_fifo_a_device_and_a_folder_are_refused_naming_the_option(tmp_path: Path, create: bool) -> None:
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    folder = tmp_path / "sub"
    folder.mkdir()
    for path, words in ((fifo, r"is a FIFO \(named pipe\), not a database file"),
                        (Path("/dev/zero"), "is a character device, not a database file"),
                        (folder, "is a folder, not a database file")):
        with pytest.raises(InputError, match=f"^--db: {path} {words}$"):
            check_store(locate(path), create=create)


def test_a_regular_store_file_passes(tmp_path: Path) -> None:
    db = tmp_path / "s.db"
    db.write_bytes(b"")
    check_store(locate(db), create=False)
