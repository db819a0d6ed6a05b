"""Errors the user can act on.

Everything the user typed or supplied (a file, a flag, a config key) that is wrong raises `InputError`
with a one-line message naming the file, line, column or field. The CLI turns it into exit code 2 and
that single line on stderr; library callers catch it like any ValueError.
"""


class HilError(Exception):
    """Base of the errors hil raises on purpose (as opposed to bugs)."""


class InputError(HilError, ValueError):
    """Bad input: the message names the file/line/column/field and says what is wrong."""


class UnknownRobotError(InputError):
    """A robot type that is not in the catalog."""


class FaultError(HilError):
    """Something the station needs is not there: a device or a database server that does not answer.
    Not bad input and not a bug: the CLI exits 3 (a station fault), and what was recorded stays."""
