"""What the subcommands print: JSON or a person's summary on stdout, "wrote FILE" lines on stderr,
figures in millimetres, and a quiet end (exit 141) when stdout's reader goes away."""

from __future__ import annotations

import json
import sys
from typing import Any


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


class _GuardedStdout:
    """A stand-in for ``sys.stdout`` that tells a closed stdout apart from other broken pipes."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return int(self._stream.write(text))
        except BrokenPipeError as exc:
            raise StdoutClosed(*exc.args) from None

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError as exc:
            raise StdoutClosed(*exc.args) from None

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def quiet_on_closed_stdout(func: Any) -> Any:
    """`func(args)` of a subcommand, ending quietly (exit code 141) when stdout's reader goes away."""

    def run(args: Any) -> Any:
        stream = sys.stdout
        sys.stdout = _GuardedStdout(stream)  # type: ignore[assignment]
        try:
            code = func(args)
            sys.stdout.flush()
            return code
        except StdoutClosed:
            try:  # what is left in the buffer must not fail again when the interpreter exits
                import os

                os.dup2(os.open(os.devnull, os.O_WRONLY), stream.fileno())
            except (AttributeError, OSError, ValueError):
                pass  # not a real file (captured in a test): nothing to silence
            return EXIT_STDOUT_CLOSED
        finally:
            sys.stdout = stream

    run.__wrapped__ = func  # type: ignore[attr-defined]
    return run
