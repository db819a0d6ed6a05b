"""Reading the files a user names, with one wording for every way that can fail.

Every reader of user files (configs, programs, models, measurement tables) goes through here so the
one-line `InputError` always names the file and says the same thing for the same fault.
"""

from __future__ import annotations

import os
from pathlib import Path

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
