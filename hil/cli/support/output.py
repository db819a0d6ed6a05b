"""What the subcommands print: JSON or a person's summary on stdout, "wrote FILE" lines on stderr,
figures in millimetres, and a quiet end (exit 141) when stdout's reader goes away."""

from __future__ import annotations

import codecs
import contextlib
import errno
import io
import json
import os
import stat
import sys
from typing import Any

from hil.errors import InputError

#: ASCII for the non-ASCII characters hil's words use (units, statistics, typography), so a terminal or
#: a log in ASCII (``PYTHONIOENCODING=ascii``, the C locale) reads them; anything else becomes "?".
ASCII_SPELLINGS: dict[str, str] = {
    "\u2014": "--", "\u2013": "-", "\u2212": "-", "\u2026": "...", "\u00b5": "u", "\u03bc": "u",
    "\u00b0": " deg", "\u00b1": "+/-", "\u00d7": "x", "\u00b7": ".", "\u2248": "~", "\u2264": "<=",
    "\u2265": ">=", "\u2192": "->", "\u2190": "<-", "\u00b2": "^2", "\u00b3": "^3", "\u03c3": "sigma",
    "\u03c1": "rho", "\u0394": "delta", "\u03b8": "theta", "\u03c0": "pi", "\u2018": "'", "\u2019": "'",
    "\u201c": '"', "\u201d": '"', "\u2022": "*", "\u2713": "ok", "\u2717": "x", "\u00a0": " ",
}
ASCII_ERRORS = "hil-ascii"


def _to_ascii(exc: UnicodeError) -> tuple[str, int]:
    """The codec error handler behind `ASCII_ERRORS`: each character the stream cannot encode spelled
    in ASCII (`ASCII_SPELLINGS`, else its decomposition's ASCII letters, else "?")."""
    if not isinstance(exc, UnicodeEncodeError):
        raise exc
    import unicodedata

    out = []
    for ch in exc.object[exc.start:exc.end]:
        spelled = ASCII_SPELLINGS.get(ch)
        if spelled is None:
            spelled = unicodedata.normalize("NFKD", ch).encode("ascii", "ignore").decode() or "?"
        out.append(spelled)
    return "".join(out), exc.end


codecs.register_error(ASCII_ERRORS, _to_ascii)


def degrade_to_ascii(*streams: Any) -> None:
    """Let `streams` (default stdout and stderr) write what they cannot encode as ASCII instead of
    failing: an em dash in ``hil show`` under ``PYTHONIOENCODING=ascii`` or a C locale was exit 70
   . A stream that encodes UTF-8, or is not a text file, is left as it is."""
    for stream in streams or (sys.stdout, sys.stderr):
        encoding = (getattr(stream, "encoding", None) or "").lower().replace("_", "-")
        if encoding in ("utf-8", "utf8", "utf-16", "utf-32") or not hasattr(stream, "reconfigure"):
            continue
        with contextlib.suppress(ValueError, OSError, io.UnsupportedOperation):
            stream.reconfigure(errors=ASCII_ERRORS)


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


def check_stdout_open() -> None:
    """`StdoutUnwritable` now when there is no stdout at all (started with ``>&-``): a command whose
    output goes there says so before its work (``hil select`` searched for seconds, then failed to
    write); a full or broken one is found only by writing."""
    stream = getattr(sys.stdout, "_stream", sys.stdout)
    if stream is None or isinstance(stream, _NoStdout):
        raise _unwritable(OSError(errno.EBADF, "stdout is closed"))
    if _is_dev_full(stream):
        raise _unwritable(OSError(errno.ENOSPC, "No space left on device (stdout is /dev/full)"))


def _is_dev_full(stream: Any) -> bool:
    """Whether `stream` is the system's /dev/full, the one device known before writing to refuse
    every write (ENOSPC); /dev/null and ttys are character devices too, and take what is written."""
    try:
        mine, full = os.fstat(stream.fileno()), os.stat("/dev/full")
    except (AttributeError, OSError, ValueError):  # no descriptor (captured), or no /dev/full here
        return False
    return stat.S_ISCHR(mine.st_mode) and stat.S_ISCHR(full.st_mode) and mine.st_rdev == full.st_rdev


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
    in one line (`StdoutUnwritable`, exit 2) when stdout is full, unwritable or missing.

    A stdout that is missing or /dev/full is refused before `func` runs, for every subcommand: found
    only at the first write, it failed ``hil identify`` and ``hil fk --json`` after they had written
    their files, and a campaign after its hours of work."""

    def run(args: Any) -> Any:
        stream = sys.stdout
        sys.stdout = _GuardedStdout(stream)  # type: ignore[assignment]
        try:
            check_stdout_open()
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
