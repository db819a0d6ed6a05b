"""The `hil` command line.

Each subcommand lives in its own module of this package and exposes `register(subparsers)`. The
dispatcher below is the only place that turns exceptions into exit codes, so no subcommand prints a
traceback at the user:

* 0 — success;
* 1 — the job ran but failed (e.g. a calibration that does not pass its acceptance threshold);
* 2 — bad input (a file, a flag, a config value), with one line naming what is wrong;
* 3 — a hardware fault (robot or tracker) ended the run;
* 4 — the run was aborted;
* 130 — interrupted by Ctrl-C; in general 128 + the signal number (143 SIGTERM, 129 SIGHUP), the
  shell's convention. ``hil calibrate`` stops the arm and leaves the campaign resumable;
* 70 — an unexpected internal error (one line; ``--debug`` shows the traceback).

The top of hil: it may import every package below it; nothing imports it.
"""

from __future__ import annotations

import argparse
import functools
import importlib
import sys
from collections.abc import Sequence
from typing import Any

import hil
from hil.arm.blas_threads import limit_blas_threads
from hil.cli.support.output import degrade_to_ascii, quiet_on_closed_stdout
from hil.errors import FaultError, HilError, InputError
from hil.jobs.outcome import (
    EXIT_BAD_INPUT,
    EXIT_FAILED,
    EXIT_FAULT,
    EXIT_INTERNAL,
    EXIT_INTERRUPTED,
    EXIT_OK,
)

# Modules of hil.cli that each add one subcommand (in help order).
COMMAND_MODULES: tuple[str, ...] = (
    "calibrate",
    "verify",
    "identify",
    "validate",
    "fk",
    "export",
    "compensate",
    "synth",
    "select",
    "sim",
    "history",
    "robots",
    "robot",
    "report",
    "fleet_report",
    "moveb",
    "tui",
)

# The subcommands each module adds, with their one-line help: `hil --help` lists them from here
# without importing the modules (and what they pull in: numpy, scipy, pinocchio, matplotlib...);
# tests/hil/cli/test_help.py checks this table against what the modules register.
COMMAND_HELP: dict[str, tuple[tuple[str, str], ...]] = {
    "calibrate": (("calibrate", "run a whole calibration campaign"),),
    "verify": (("verify", "ISO 9283 pose test, uncompensated and compensated"),),
    "identify": (("identify", "identify a calibrated model from measurements"),),
    "validate": (("validate", "check a model against held-out measurements"),),
    "fk": (("fk", "forward kinematics of a model"),),
    "export": (("export", "export a model (URDF, ROS kinematics YAML, JSON)"),),
    "compensate": (("compensate", "rewrite target poses (CSV or URScript) for the controller's own model"),),
    "synth": (("synth", "write a synthetic truth and simulated measurements"),),
    "select": (("select", "choose optimal measurement poses (JSON out)"),),
    "sim": (("sim", "run the simulated station (robot + tracker)"),),
    "history": (("history", "list calibration campaigns"),
                ("show", "print one campaign; export its model or measurements")),
    "robots": (("robots", "list the fleet: robots, last calibrations, current models"),),
    "robot": (("robot", "one robot's history; mark a calibration bad or good"),),
    "report": (("report", "write the HTML report of a saved calibration or verification result"),),
    "fleet_report": (("fleet-report", "write the fleet's HTML report (accuracy over time, stations)"),),
    "moveb": (("moveb", "smooth error-controlled trajectories (plan, run)"),),
    "tui": (("tui", "the operator's terminal app (keyboard only, 80x24 and larger)"),),
}

#: hardware faults are the station's faults (`hil.jobs.outcome.EXIT_FAULT`)
EXIT_HARDWARE = EXIT_FAULT


class _ShowDefaults(argparse.HelpFormatter):
    """Adds "(default: X)" to an option's help when it has a default and the help does not say it."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text, default = action.help or "", action.default
        if (not action.option_strings or "%(default)" in text or "default" in text.lower()
                or default is None or default is False or default is argparse.SUPPRESS or default == []):
            return action.help
        return f"{text} (default: %(default)s)"


@functools.cache
def _with_defaults(formatter: type[argparse.HelpFormatter]) -> type[argparse.HelpFormatter]:
    return formatter if issubclass(formatter, _ShowDefaults) else type(
        f"{formatter.__name__}ShowingDefaults", (_ShowDefaults, formatter), {})


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as one line and exit code 2, and shows options' defaults."""

    def __init__(self, *args: Any, formatter_class: type[argparse.HelpFormatter] = argparse.HelpFormatter,
                 **kwargs: Any) -> None:
        super().__init__(*args, formatter_class=_with_defaults(formatter_class), **kwargs)

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


class _Version(argparse.Action):
    """``--version``, which looks the version up only when asked (see `hil.__getattr__`)."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: object,
                 option_string: str | None = None) -> None:
        print(f"hil {hil.__version__}")
        parser.exit(0)


def _command_of(argv: Sequence[str]) -> str:
    """The subcommand a command line names (its first word that is not an option), or ""."""
    return next((a for a in argv if not a.startswith("-")), "")


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The parser; without `argv` every subcommand is registered in full.

    Given the command line, only the module of the subcommand it names is imported and registered; the
    others are listed by name and one-line help (`COMMAND_HELP`), so ``hil --help`` or ``hil history``
    does not pay for the numerical libraries other subcommands need.
    """
    parser = _Parser(prog="hil", description="Kinematic calibration of Universal Robots arms.")
    parser.add_argument("--version", action=_Version, nargs=0, help="show hil's version and exit")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    wanted = None if argv is None else _command_of(argv)
    for name in COMMAND_MODULES:
        listed = COMMAND_HELP.get(name, ())
        if wanted is None or not listed or any(command == wanted for command, _ in listed):
            importlib.import_module(f"hil.cli.{name}").register(sub)
        else:
            for command, summary in listed:
                sub.add_parser(command, help=summary)
    _guard_stdout(parser)
    return parser


def _guard_stdout(parser: argparse.ArgumentParser) -> None:
    """Every subcommand ends quietly when its stdout's reader goes away (`quiet_on_closed_stdout`)."""
    func = parser.get_default("func")
    if func is not None and not hasattr(func, "__wrapped__"):
        parser.set_defaults(func=quiet_on_closed_stdout(func))
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                _guard_stdout(child)


def _simulator_did_not_start(exc: BaseException) -> bool:
    """Whether `exc` is the simulator's `mocks.ur.process.SimStartError` (``--sim`` runs).

    Looked up, not imported: every hil command (on a real station too) would otherwise load the
    simulator's controller and servers, and a raised SimStartError means its module is loaded already.
    """
    process = sys.modules.get("mocks.ur.process")
    return process is not None and isinstance(exc, process.SimStartError)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the process exit code. Called with no `argv` it is the ``hil`` program
    (``args.as_program``), which a command may end at once when it is done (`hil tui`); called with an
    argument list (a test, a script) it always returns."""
    as_program = argv is None
    argv = sys.argv[1:] if argv is None else list(argv)
    degrade_to_ascii()  # an ASCII terminal or the C locale: "--" for an em dash, not exit 70
    limit_blas_threads()
    try:
        parser = build_parser(argv)
    except KeyboardInterrupt:  # Ctrl-C while the subcommands' modules load
        print("hil: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # usage errors, --help and --version end here, not in the caller
        return exc.code if isinstance(exc.code, int) else EXIT_BAD_INPUT
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return EXIT_BAD_INPUT
    args.as_program = as_program
    try:
        return int(args.func(args) or EXIT_OK)
    except InputError as exc:
        print(f"hil: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except FaultError as exc:  # a device or the database server is not there: a station fault
        print(f"hil: fault: {exc}", file=sys.stderr)
        return EXIT_HARDWARE
    except HilError as exc:
        print(f"hil: failed: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except KeyboardInterrupt as exc:  # Ctrl-C, or a RunInterrupted (SIGTERM, SIGHUP) outside a run
        signum = getattr(exc, "signum", None)
        print(f"hil: interrupted{f' ({exc})' if signum else ''}", file=sys.stderr)
        return EXIT_INTERRUPTED if signum is None else 128 + signum
    except Exception as exc:  # the one place that keeps tracebacks away from the user
        if _simulator_did_not_start(exc):  # a station that does not come up is a fault, not a bug
            print(f"hil: hardware fault: the simulated station did not start: {exc}", file=sys.stderr)
            return EXIT_HARDWARE
        if args.debug:
            raise
        print(f"hil: internal error: {type(exc).__name__}: {exc} (rerun with --debug for details)",
              file=sys.stderr)
        return EXIT_INTERNAL
