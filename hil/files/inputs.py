"""Reading the files a user names, with one wording for every way that can fail.

Every reader of user files (configs, programs, models, measurement tables) goes through here so the
one-line `InputError` always names the file and says the same thing for the same fault.
"""

from __future__ import annotations

import csv
import io
import json
import os
import stat
from typing import Any

from hil.errors import InputError

#: The largest input file hil reads (bytes). The largest a person or an instrument writes for hil is a
#: measurements CSV: 10 000 rows of 15 columns (the identification's row limit, `MAX_FIT_ROWS` of
#: hil.cli.identify) are about 3 MB, a URScript program of 100 000 waypoints about 10 MB. 64 MiB is
#: an assumption — twenty times that, yet small enough that reading it whole cannot exhaust a station
#: PC's memory — and it bounds what a wrong path (a disk image, a log) costs before it is refused.
MAX_INPUT_BYTES = 64 << 20


def _size(n: int) -> str:
    return f"{n / (1 << 20):.0f} MiB" if n >= 1 << 20 else f"{n} bytes"


def read_input_bytes(path: str | os.PathLike[str], expected: str = "a file",
                     limit: int = MAX_INPUT_BYTES) -> bytes:
    """The file's bytes; InputError naming it when it is missing, a directory, unreadable, not a
    regular file, or larger than `limit` bytes.

    The one place hil opens a user's input, so every input is bounded the same way: the file is opened
    without blocking (a FIFO with no writer would otherwise wait forever in open()), anything but a
    regular file is refused (``/dev/zero``, ``/dev/urandom`` and FIFOs never end), and at most
    `limit` + 1 bytes are read, so a file that grows while it is read is refused too.
    """
    name = str(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise InputError(f"{name}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{name}: is a directory, expected {expected}") from None
    except OSError as exc:
        raise InputError(f"{name}: cannot read: {exc.strerror or exc}") from None
    try:
        info = os.fstat(fd)
        if stat.S_ISDIR(info.st_mode):
            raise InputError(f"{name}: is a directory, expected {expected}")
        if not stat.S_ISREG(info.st_mode):
            raise InputError(f"{name}: is {file_kind(info.st_mode)}, not a regular file; expected {expected}")
        if info.st_size > limit:
            raise InputError(f"{name}: {_size(info.st_size)} is larger than hil reads "
                             f"({_size(limit)}); expected {expected}")
        os.set_blocking(fd, True)
        chunks, total = [], 0
        while total <= limit:
            chunk = os.read(fd, min(1 << 20, limit + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
        if total > limit:
            raise InputError(f"{name}: larger than hil reads ({_size(limit)}); expected {expected}")
        return b"".join(chunks)
    except OSError as exc:
        raise InputError(f"{name}: cannot read: {exc.strerror or exc}") from None
    finally:
        os.close(fd)


def file_kind(mode: int) -> str:
    """What a file that is not a regular file is, in words (inputs' and outputs' refusals)."""
    for test, words in ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                        (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return words
    return "not a regular file"


def read_input_text(path: str | os.PathLike[str], expected: str = "a text file") -> str:
    """The file as UTF-8 text (a byte-order mark, as spreadsheets write, is dropped)."""
    return decode_input_text(read_input_bytes(path, expected), str(path))


def decode_input_text(raw: bytes, name: str) -> str:
    """`raw` as UTF-8 text (byte-order mark dropped); InputError naming `name` and the bad byte."""
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{name}: not a UTF-8 text file (byte {exc.start})") from None


def parse_json(text: str, name: str) -> Any:
    """`text` parsed as JSON; InputError naming `name` for any way it can fail to parse.

    Besides syntax errors, Python's parser fails on input no sane writer produces but an attacker (or a
    broken tool) can: nesting deep enough to exhaust the recursion limit, and integers longer than the
    interpreter's digit limit. Both would otherwise escape as internal errors.
    """
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{name}: line {exc.lineno}: not valid JSON ({exc.msg})") from None
    except RecursionError:
        raise InputError(f"{name}: not a usable JSON file (nested too deeply)") from None
    except ValueError as exc:  # e.g. "Exceeds the limit (4300 digits) for integer string conversion"
        raise InputError(f"{name}: not a usable JSON file ({exc})") from None


#: The most data rows hil reads from one CSV table (measurements, joints, targets). A campaign has at
#: most 1000 calibration and 1000 validation poses (`hil.cli.support.options.POSE_COUNT`), so 10 000 is
#: five times the largest file hil itself writes; `hil identify` fits 10 000 rows in about a minute
#: (docs/design.md, Measurements CSV: the figure and the command that measures it), while a 100 000-row
#: file ran over 20 minutes (issue 31). A table beyond it is refused before its values are parsed.
MAX_TABLE_ROWS = 10_000


def csv_rows(text: str, name: str, limit: int = MAX_TABLE_ROWS) -> list[tuple[int, list[str]]]:
    """The rows of CSV `text` with their 1-based line numbers; InputError naming file and line when
    the csv module refuses a row (a field over its size limit, a NUL byte), which it raises as its own
    `csv.Error` and would otherwise escape as an internal error, and when the table has more than
    `limit` rows besides its header (comments and blank rows are not counted)."""
    reader = csv.reader(io.StringIO(text))
    rows: list[tuple[int, list[str]]] = []
    number = 0
    counted = 0
    try:
        for number, row in enumerate(reader, start=1):
            rows.append((number, row))
            if row and any(c.strip() for c in row) and not row[0].lstrip().startswith("#"):
                counted += 1
                if counted > limit + 1:  # the header and `limit` rows
                    raise InputError(f"{name}: line {reader.line_num}: more than {limit} rows; hil reads "
                                     f"tables of at most {limit} rows (split the file)")
    except csv.Error as exc:
        line = max(reader.line_num, number + 1)  # the physical line the reader stopped on
        raise InputError(f"{name}: line {line}: not a usable CSV row ({exc})") from None
    return rows


def json_number(value: Any, where: str, quantity: str) -> float:
    """`value` as a float when it is a real JSON number of `quantity` (a row of
    `hil.files.quantities.QUANTITIES`); InputError naming `where` ("model.json: joints[2].xyz[0]") and
    the quantity's range otherwise. JSON `true` and the string "1" are not numbers."""
    from hil.files.quantities import quantity as row

    return row(quantity).json(value, where)
