"""Reading the files a user names, with one wording for every way that can fail.

Every reader of user files (configs, programs, models, measurement tables) goes through here so the
one-line `InputError` always names the file and says the same thing for the same fault.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from pathlib import Path
from typing import Any

from hil.errors import InputError


def read_input_bytes(path: str | os.PathLike[str], expected: str = "a file") -> bytes:
    """The file's bytes; InputError naming it when it is missing, a directory or unreadable."""
    name = str(path)
    try:
        return Path(path).read_bytes()
    except FileNotFoundError:
        raise InputError(f"{name}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{name}: is a directory, expected {expected}") from None
    except OSError as exc:
        raise InputError(f"{name}: cannot read: {exc.strerror or exc}") from None


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


def csv_rows(text: str, name: str) -> list[tuple[int, list[str]]]:
    """The rows of CSV `text` with their 1-based line numbers; InputError naming file and line when
    the csv module refuses a row (a field over its size limit, a NUL byte), which it raises as its own
    `csv.Error` and would otherwise escape as an internal error."""
    reader = csv.reader(io.StringIO(text))
    rows: list[tuple[int, list[str]]] = []
    number = 0
    try:
        for number, row in enumerate(reader, start=1):
            rows.append((number, row))
    except csv.Error as exc:
        line = max(reader.line_num, number + 1)  # the physical line the reader stopped on
        raise InputError(f"{name}: line {line}: not a usable CSV row ({exc})") from None
    return rows


def json_number(value: Any, where: str, low: float, high: float, unit: str = "") -> float:
    """`value` as a float when it is a real JSON number within [low, high]; InputError otherwise.

    `where` names the file and field ("model.json: joints[2].xyz[0]"). JSON `true` and the string "1"
    are not numbers even though Python's float() takes them: a file that holds them was not written
    by a tool that meant a number, and silently reading them as 1.0 hides the mistake.
    """
    if isinstance(value, bool) or not isinstance(value, int | float):
        shown = json.dumps(value) if isinstance(value, str | bool) or value is None else type(value).__name__
        if len(shown) > 40:
            shown = shown[:37] + "..."
        raise InputError(f"{where}: expected a number, got {shown}")
    try:
        number = float(value)
    except OverflowError:  # an integer with hundreds of digits
        raise InputError(f"{where}: expected a finite number, got an integer of "
                         f"{len(str(abs(value)))} digits") from None
    if not math.isfinite(number):
        raise InputError(f"{where}: expected a finite number, got {number}")
    if not low <= number <= high:
        suffix = f" {unit}" if unit else ""
        raise InputError(f"{where}: {number:g}{suffix} is outside the plausible range "
                         f"[{low:g}, {high:g}]{suffix}")
    return number
