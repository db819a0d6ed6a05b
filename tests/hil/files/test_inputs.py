"""Every way a named file can fail to be read gives one line naming the file."""

from __future__ import annotations

import os

import pytest

from hil.calibration.measurement_forms import read_rows
from hil.calibration.model_file import read_json
from hil.errors import InputError
from hil.files.inputs import read_input_text
from hil.moveb.program import load_program
from hil.station.config import load_config

READERS = [
    (load_config, "a TOML file"),
    (read_json, "a JSON file"),
    (load_program, "a MOVEB program"),
    (read_rows, "a CSV file"),
]


@pytest.mark.parametrize(("reader", "expected"), READERS)
def test_missing_directory_and_binary_files_are_named(tmp_path, reader, expected) -> None:
    with pytest.raises(InputError, match=r"nope\.txt: no such file$"):
        reader(tmp_path / "nope.txt")
    with pytest.raises(InputError, match=f"{tmp_path.name}: is a directory, expected {expected}$"):
        reader(tmp_path)
    binary = tmp_path / "binary.txt"
    binary.write_bytes(b"ok\n\xff\xfe")
    with pytest.raises(InputError, match=r"binary\.txt: not a UTF-8 text file \(byte 3\)$"):
        reader(binary)


def test_an_unreadable_file_is_named(tmp_path, monkeypatch) -> None:
    f = tmp_path / "locked.toml"
    f.write_text("a = 1\n")

    def refuse(path: object, flags: int, *args: object) -> int:  # chmod 0 does not stop root
        raise PermissionError(13, "Permission denied", str(path))

    with monkeypatch.context() as patch, pytest.raises(
            InputError, match=r"locked\.toml: cannot read: Permission denied$"):
        patch.setattr(os, "open", refuse)
        read_input_text(f)


def test_a_byte_order_mark_is_dropped(tmp_path) -> None:
    f = tmp_path / "excel.csv"
    f.write_bytes("\ufeffx\n1\n".encode())
    assert read_input_text(f) == "x\n1\n"
