"""What the subcommands print: JSON or a person's summary on stdout, "wrote FILE" lines on stderr,
figures in millimetres, and a quiet end (exit 141) when stdout's reader goes away."""

from __future__ import annotations

import contextlib
import errno
import json
import os
import sys
from typing import Any

from hil.errors import InputError


def mm(value: float) -> str:
    """Metres shown as millimetres with µm resolution."""
    return f"{value * 1e3:.3f} mm"



def say(text: str, severity: str = "information") -> None:
    """A job's words (`hil.jobs.words.Say`) on stderr, as every line hil says: ``hil: <text>``."""
    print(f"hil: {text}", file=sys.stderr, flush=True)


def print_json(doc: Any) -> None:
    """One JSON document on stdout."""
    json.dump(doc, sys.stdout, indent=2)
    sys.stdout.write("\n")


def wants_json(args: Any) -> bool:
    """JSON on stdout when asked (``--json``) or when stdout is not a terminal (a pipe, a file: scripts
    read JSON, as they always did); a readable summary on a terminal."""
    return bool(getattr(args, "json", False)) or not sys.stdout.isatty()


def wrote(path: Any, what: str = "") -> None:
    """The one line every command that writes a file prints: on stderr, so stdout stays clean."""
    print(f"wrote {path}" + (f" ({what})" if what else ""), file=sys.stderr)


#: Exit code of a command whose reader closed stdout early (``hil show last --json | head -1``):
#: 128 + SIGPIPE, what the shell reports for any Unix tool that stopped writing for that reason.
EXIT_STDOUT_CLOSED = 141


class StdoutClosed(BrokenPipeError):
    """Stdout's reader went away (as opposed to a broken pipe to a device)."""


class StdoutUnwritable(InputError):
    """Stdout cannot take the output: a full device (``> /dev/full``), a file system gone read-only, or
    no stdout at all (started with ``>&-``). The user's surroundings, not a bug: one line, exit 2."""


class _NoStdout:
    """What stands for stdout when the process was started without one (Python sets it to None)."""

    def write(self, text: str) -> int:
        raise OSError(errno.EBADF, "stdout is closed")

    def flush(self) -> None:
        pass


class _GuardedStdout:
    """A stand-in for ``sys.stdout`` that tells a closed stdout apart from other broken pipes, and
    turns any other failed write into a one-line `StdoutUnwritable`."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream if stream is not None else _NoStdout()

    def write(self, text: str) -> int:
        try:
            return int(self._stream.write(text))
        except BrokenPipeError as exc:
            raise StdoutClosed(*exc.args) from None
        except OSError as exc:
            raise _unwritable(exc) from None

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError as exc:
            raise StdoutClosed(*exc.args) from None
        except OSError as exc:
            raise _unwritable(exc) from None

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def _unwritable(exc: OSError) -> StdoutUnwritable:
    return StdoutUnwritable(f"stdout: cannot write the output: {exc.strerror or exc}")


def _silence(stream: Any) -> None:
    """Point `stream`'s file descriptor at /dev/null, so what is left in its buffer does not fail
    again (and print a second error) when the interpreter flushes it at exit."""
    # not a real file (captured in a test), or no stdout at all: nothing to silence
    with contextlib.suppress(AttributeError, OSError, ValueError):
        os.dup2(os.open(os.devnull, os.O_WRONLY), stream.fileno())


def quiet_on_closed_stdout(func: Any) -> Any:
    """`func(args)` of a subcommand, ending quietly (exit code 141) when stdout's reader goes away, and
    in one line (`StdoutUnwritable`, exit 2) when stdout is full, unwritable or missing."""

    def run(args: Any) -> Any:
        stream = sys.stdout
        sys.stdout = _GuardedStdout(stream)  # type: ignore[assignment]
        try:
            code = func(args)
            sys.stdout.flush()
            return code
        except StdoutClosed:
            _silence(stream)
            return EXIT_STDOUT_CLOSED
        except StdoutUnwritable:
            _silence(stream)
            raise
        finally:
            sys.stdout = stream

    run.__wrapped__ = func  # type: ignore[attr-defined]
    return run
