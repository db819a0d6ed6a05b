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


#: The largest station TOML hil reads (bytes). The example config, every key documented, is about
#: 8 KB; 1 MiB is an assumption (a hundred times that) under which tomllib, a pure-Python parser,
#: reads any file in well under a second — 60 MB of TOML kept it busy for over a minute.
MAX_CONFIG_BYTES = 1 << 20

#: The largest JSON document hil reads (a model, truth, controller calibration or result; bytes). The
#: largest hil writes is a hil-result/1 with its per-pose block, about 100 KB for a campaign of 50
#: poses and some MB for the 2000 a campaign may have; 16 MiB is an assumption above that, under
#: which the json module parses any file in about a second (60 MB of one array took 3 s of CPU and
#: 2 GB of memory before it was refused as "not an object").
MAX_JSON_BYTES = 16 << 20


def _size(n: int) -> str:
    return f"{n / (1 << 20):.0f} MiB" if n >= 1 << 20 else f"{n} bytes"


def _open_input(path: str | os.PathLike[str], expected: str, limit: int) -> tuple[int, int]:
    """(descriptor, size) of input `path` opened for reading; InputError naming it when it is missing,
    a directory, unreadable, not a regular file, or larger than `limit` bytes. Opened without blocking
    (a FIFO with no writer would otherwise wait forever in open()); the caller closes it."""
    name = str(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise InputError(f"{name}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{name}: is a directory, expected {expected}") from None
    except OSError as exc:
        try:  # a socket cannot be opened at all (ENXIO): say what it is rather than the OS's words
            mode = os.stat(path).st_mode
        except OSError:
            mode = stat.S_IFREG
        if not stat.S_ISREG(mode):
            kind = file_kind(mode)
            raise InputError(f"{name}: is {kind}, not a regular file; expected {expected}") from None
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
    except BaseException:
        os.close(fd)
        raise
    return fd, info.st_size


def check_input_file(path: str | os.PathLike[str], expected: str = "a file",
                     limit: int = MAX_INPUT_BYTES) -> None:
    """InputError naming `path` when `read_input_bytes` would refuse it for what it is (missing, a
    directory, a device, a FIFO, a socket, over `limit` bytes), found without reading it: the command
    line checks its input files with it (`hil.cli.support.options.input_file`) before a command loads
    the libraries it computes with, so such a file is refused in a fraction of a second."""
    fd, _ = _open_input(path, expected, limit)
    os.close(fd)


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
    fd, _ = _open_input(path, expected, limit)
    try:
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


#: The most lines hil reads from a file that is read line by line (a CSV table, a MOVEB or URScript
#: program, a station TOML). The longest such file hil is meant for is a URScript program of 100 000
#: waypoints (see `MAX_INPUT_BYTES`); one million lines is an assumption — ten times that — which
#: bounds what a file of nothing but newlines or comments costs: 60 MB of them fits under
#: `MAX_INPUT_BYTES` yet took the CSV, MOVEB and TOML readers minutes to walk line by line.
MAX_TEXT_LINES = 1_000_000

#: The longest line hil reads from such a file (characters). A measurements or pose row is a few
#: hundred characters, a URScript list literal of a thousand poses about 60 000; 1 Mi is an assumption
#: — sixteen times that — under which every reader splits a line in well under a second, while one
#: 60 MB line of 20 million CSV fields took longer than a minute.
MAX_LINE_CHARS = 1 << 20


def read_input_text(path: str | os.PathLike[str], expected: str = "a text file", *,
                    line_based: bool = True, limit: int = MAX_INPUT_BYTES) -> str:
    """The file as UTF-8 text (a byte-order mark, as spreadsheets write, is dropped), at most `limit`
    bytes, and bounded as `check_text_lines` says unless `line_based` is False (JSON, whose writers
    may put a whole document on one line)."""
    raw = read_input_bytes(path, expected, limit)
    return decode_input_text(raw, str(path), expected if line_based else None)


def decode_input_text(raw: bytes, name: str, expected: str | None = "a text file") -> str:
    """`raw` as UTF-8 text (byte-order mark dropped); InputError naming `name` and the bad byte.

    With `expected` (the kind of file, for the error) the text is also held to `check_text_lines`.
    """
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{name}: not a UTF-8 text file (byte {exc.start})") from None
    if expected is not None:
        check_text_lines(text, name, expected)
    return text


def check_text_lines(text: str, name: str, expected: str = "a text file") -> None:
    """InputError naming `name` when `text` has more than `MAX_TEXT_LINES` lines or a line longer
    than `MAX_LINE_CHARS` (naming that line).

    The one bound of every reader that walks a file line by line: the byte limit alone lets 64 MiB of
    newlines, or one line of 20 million fields, through to readers whose time grows with the lines or
    the fields. Counting is done by C loops (``str.count``, ``str.splitlines``) so the refusal itself
    takes a fraction of a second.
    """
    lines = text.count("\n") + (not text.endswith("\n"))
    if lines > MAX_TEXT_LINES:
        raise InputError(f"{name}: {lines} lines; hil reads at most {MAX_TEXT_LINES} lines of "
                         f"{expected} (split the file)")
    if len(text) <= MAX_LINE_CHARS:
        return
    split = text.split("\n")
    longest = max(split, key=len)
    if len(longest) > MAX_LINE_CHARS:
        line = split.index(longest) + 1
        raise InputError(f"{name}: line {line}: {len(longest)} characters long; hil reads lines of at most "
                         f"{MAX_LINE_CHARS} characters in {expected}")


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
#: file ran over 20 minutes. A table beyond it is refused before its values are parsed.
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
