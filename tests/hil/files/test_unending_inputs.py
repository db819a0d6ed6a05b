"""Inputs that never end (devices, FIFOs) and inputs too large are refused at open, in one line.

The one reader (`hil.files.inputs.read_input_bytes`) opens without blocking, refuses what is not a
regular file and reads at most its limit, so no reader of hil can hang on ``/dev/zero`` or a FIFO
with no writer (issue 31, class 1).
"""

from __future__ import annotations

import os
import threading
import time

import pytest

from hil.calibration.measurements import read_measurements
from hil.errors import InputError
from hil.files.inputs import MAX_INPUT_BYTES, MAX_TABLE_ROWS, csv_rows, read_input_bytes
from tests.hil.files.test_inputs import READERS


@pytest.mark.timeout(20)
@pytest.mark.parametrize(("reader", "expected"), READERS)
def test_devices_and_a_fifo_without_writer_are_refused_at_once(tmp_path, reader, expected) -> None:
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for path, kind in (("/dev/zero", "a character device"), ("/dev/urandom", "a character device"),
                       (str(fifo), r"a FIFO \(named pipe\)")):
        start = time.monotonic()
        with pytest.raises(InputError, match=f"{path.rsplit('/', 1)[-1]}: is {kind}, not a regular file; "
                                             f"expected {expected}$"):
            reader(path)
        assert time.monotonic() - start < 1.0


def test_a_file_larger_than_the_limit_is_refused_with_the_limit(tmp_path) -> None:
    big = tmp_path / "big.csv"
    big.write_bytes(b"q1\n" + b"0\n" * 600)
    assert len(read_input_bytes(big, limit=2000)) == 1203  # under its limit: read whole
    with pytest.raises(InputError, match=r"big\.csv: 1203 bytes is larger than hil reads \(1000 bytes\)"):
        read_input_bytes(big, limit=1000)
    assert MAX_INPUT_BYTES == 64 << 20  # the limit docs/design.md and the README state


def test_a_file_that_grows_while_read_is_cut_at_the_limit(tmp_path, monkeypatch) -> None:
    """The size at open is not trusted: reading stops one byte past the limit whatever fstat said."""
    grows = tmp_path / "grows.csv"
    grows.write_bytes(b"x" * 100)
    real_fstat = os.fstat

    def small(fd: int) -> os.stat_result:
        info = real_fstat(fd)
        return os.stat_result((info.st_mode, *info[1:6], 10, *info[7:]))

    monkeypatch.setattr(os, "fstat", small)
    with pytest.raises(InputError, match=r"grows\.csv: larger than hil reads \(50 bytes\)"):
        read_input_bytes(grows, limit=50)


@pytest.mark.timeout(20)
def test_a_fifo_with_a_writer_is_still_refused(tmp_path) -> None:
    """A pipe is refused even when something writes into it: its end is not known in advance."""
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)

    def write() -> None:
        try:
            fd = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
            os.write(fd, b"q1,q2\n")
            os.close(fd)
        except OSError:
            pass  # no reader (yet, or any more)

    threading.Thread(target=write, daemon=True).start()
    with pytest.raises(InputError, match="not a regular file"):
        read_input_bytes(fifo, "a CSV file")


def test_a_table_longer_than_the_row_limit_is_refused_at_the_first_row_past_it() -> None:
    text = "q1\n# a comment\n\n" + "0\n" * 5
    assert len(csv_rows(text, "t.csv", limit=5)) == 8  # header + 5 rows: read, comments not counted
    with pytest.raises(InputError, match=r"^t\.csv: line 8: more than 4 rows; hil reads tables of at most "
                                         r"4 rows \(split the file\)$"):
        csv_rows(text, "t.csv", limit=4)
    assert MAX_TABLE_ROWS == 10_000  # the limit docs/design.md and the README state


def test_a_100000_row_measurements_file_is_refused_in_well_under_two_seconds(tmp_path) -> None:
    """The file of the issue: refused before its values are parsed (parsing alone took 20 s)."""
    row = "0.1,-1.2,1.3,-1.4,1.5,0.6,1.1,0.2,0.3\n"
    big = tmp_path / "big.csv"
    big.write_text("q1,q2,q3,q4,q5,q6,x,y,z\n" + row * 100_000)
    start = time.process_time()
    with pytest.raises(InputError, match=r"big\.csv: line 10002: more than 10000 rows"):
        read_measurements(big)
    assert time.process_time() - start < 2.0
