"""The `hil` command line.

Each subcommand lives in its own module of this package and exposes `register(subparsers)`. The
dispatcher below is the only place that turns exceptions into exit codes, so no subcommand prints a
traceback at the user:

* 0 — success;
* 1 — the job ran but failed (e.g. a calibration that does not pass its acceptance threshold);
* 2 — bad input (a file, a flag, a config value), with one line naming what is wrong;
* 3 — a hardware fault (robot or tracker) ended the run;
* 4 — the run was aborted;
* 70 — an unexpected internal error (one line; ``--debug`` shows the traceback).

The top of hil: it may import every package below it; nothing imports it.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from hil import __version__
from hil.errors import HilError, InputError

# Modules of hil.cli that each add one subcommand (in help order).
COMMAND_MODULES: tuple[str, ...] = (
    "calibrate",
    "identify",
    "validate",
    "fk",
    "export",
    "synth",
    "select",
    "sim",
    "history",
    "report",
    "moveb",
    "tui",
)

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_BAD_INPUT = 2
EXIT_HARDWARE = 3
EXIT_ABORTED = 4
EXIT_INTERNAL = 70


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as one line and exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    """The parser with every subcommand registered."""
    parser = _Parser(prog="hil", description="Kinematic calibration of Universal Robots arms.")
    parser.add_argument("--version", action="version", version=f"hil {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in COMMAND_MODULES:
        importlib.import_module(f"hil.cli.{name}").register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the process exit code."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # usage errors, --help and --version end here, not in the caller
        return exc.code if isinstance(exc.code, int) else EXIT_BAD_INPUT
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return EXIT_BAD_INPUT
    try:
        return int(args.func(args) or EXIT_OK)
    except InputError as exc:
        print(f"hil: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except HilError as exc:
        print(f"hil: failed: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except KeyboardInterrupt:
        print("hil: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # the one place that keeps tracebacks away from the user
        if args.debug:
            raise
        print(f"hil: internal error: {type(exc).__name__}: {exc} (rerun with --debug for details)",
              file=sys.stderr)
        return EXIT_INTERNAL
