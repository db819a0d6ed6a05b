"""Errors the user can act on.

Everything the user typed or supplied (a file, a flag, a config key) that is wrong raises `InputError`
with a one-line message naming the file, line, column or field. The CLI turns it into exit code 2 and
that single line on stderr; library callers catch it like any ValueError.
"""


#: Exit codes of the command line (docs/design.md, Contracts: exit codes), one table for every package.
EXIT_OK = 0  # done: accepted, finished
EXIT_FAILED = 1  # ran, but did not pass: a calibration above its threshold, a path measured too little
EXIT_BAD_INPUT = 2  # `InputError`: a file, a flag, a configuration value; one line naming it
EXIT_FAULT = 3  # `FaultError` and the drivers' errors: the station, a device or database that does not answer
EXIT_ABORTED = 4  # aborted by the operator (final)
EXIT_INTERRUPTED = 130  # Ctrl-C; in general 128 + the signal number (143 SIGTERM, 129 SIGHUP)
EXIT_INTERNAL = 70  # a bug: one line (``--debug`` shows the traceback)


class HilError(Exception):
    """Base of the errors hil raises on purpose (as opposed to bugs)."""


class InputError(HilError, ValueError):
    """Bad input: the message names the file/line/column/field and says what is wrong."""


class UnknownRobotError(InputError):
    """A robot type that is not in the catalog."""


class FaultError(HilError):
    """Something the station needs is not there: a device or a database server that does not answer.
    Not bad input and not a bug: the CLI exits 3 (a station fault), and what was recorded stays."""
