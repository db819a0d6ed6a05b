"""An output is a regular file in a folder that exists; anything else is one line before any work,
and a write that fails names the path and the OS's reason (issue 31, class 2)."""

from __future__ import annotations

import errno
import os

import pytest

from hil.errors import InputError
from hil.files.outputs import atomic_write_text, check_output, check_output_dir


@pytest.mark.parametrize(("path", "says"), [
    ("/dev/full", "/dev/full is a character device, not a regular file"),
    ("/dev/null", "/dev/null is a character device, not a regular file"),
])
def test_devices_are_refused(path, says) -> None:
    with pytest.raises(InputError, match=f"^--out: {says}"):
        check_output(path, field="--out")


def test_a_fifo_and_a_link_to_a_device_are_refused(tmp_path) -> None:
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "full.json").symlink_to("/dev/full")
    with pytest.raises(InputError, match=r"fifo is a FIFO \(named pipe\), not a regular file"):
        check_output(tmp_path / "fifo", field="--out")
    with pytest.raises(InputError, match=r"full\.json is a character device"):
        check_output(tmp_path / "full.json", field="--out")


def test_a_trailing_slash_names_a_directory(tmp_path) -> None:
    with pytest.raises(InputError, match=r"^--out: .*new\.json/ ends in a slash, which names a directory"):
        check_output(f"{tmp_path}/new.json/", field="--out")


def test_a_name_longer_than_the_file_system_allows_is_refused(tmp_path) -> None:
    name = "a" * 300 + ".json"
    with pytest.raises(InputError, match=r"^--out: the file name a+\.\.\. is 305 bytes long; this file "
                                         r"system allows at most \d+$"):
        check_output(tmp_path / name, field="--out")
    with pytest.raises(InputError, match=r"^--out-dir: the file name a+\.\.\. is 305 bytes long"):
        check_output_dir(tmp_path / name, field="--out-dir")
    ok = tmp_path / ("b" * 250)  # a long name the file system takes: written (its temporary file too)
    check_output(ok, field="--out")
    atomic_write_text(ok, "x")
    assert ok.read_text() == "x"


def test_a_regular_file_in_an_existing_folder_is_taken(tmp_path) -> None:
    (tmp_path / "old.json").write_text("{}")
    assert check_output(tmp_path / "old.json", field="--out") == tmp_path / "old.json"
    assert check_output(tmp_path / "new.json", field="--out") == tmp_path / "new.json"


def test_a_write_that_fails_names_the_path_and_the_reason(tmp_path, monkeypatch) -> None:
    real_replace = os.replace

    def full(src, dst):  # what a full disk or quota does to the last step
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "replace", full)
    with pytest.raises(InputError, match=r"out\.json: cannot write: No space left on device$"):
        atomic_write_text(tmp_path / "out.json", "{}")
    monkeypatch.setattr(os, "replace", real_replace)
    assert list(tmp_path.iterdir()) == []  # no temporary file left behind
