"""The command line's help: every option explained, defaults shown, in the user's words, and cheap —
``hil --help`` imports none of the numerical libraries (a test of modules, not of time; the time is
measured by ``bench/cli_startup.py``)."""

from __future__ import annotations

import argparse
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

import hil.cli
from hil.cli import COMMAND_HELP, COMMAND_MODULES, build_parser

ROOT = Path(__file__).resolve().parents[3]
HEAVY = ("scipy", "matplotlib", "pinocchio")


def _parsers(parser: argparse.ArgumentParser, path: tuple[str, ...] = ("hil",)
             ) -> Iterator[tuple[tuple[str, ...], argparse.ArgumentParser]]:
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                yield from _parsers(child, (*path, name))


def _options(parser: argparse.ArgumentParser) -> Iterator[argparse.Action]:
    return (a for a in parser._actions if not isinstance(a, (argparse._SubParsersAction,
                                                                argparse._HelpAction)))


def _loaded_by(argv: list[str]) -> tuple[int, list[str]]:
    """(exit code, the top-level packages of `HEAVY` and numpy) after `hil ARGV` in a fresh interpreter."""
    code = ("import contextlib, io, sys\n"
            "from hil.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            f"    rc = main({argv!r})\n"
            "top = {m.split('.')[0] for m in sys.modules}\n"
            f"print(rc, ','.join(sorted(top & {{*{HEAVY!r}, 'numpy'}})))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    rc, _, loaded = out.stdout.strip().partition(" ")
    return int(rc), [m for m in loaded.split(",") if m]


def test_hil_help_imports_no_numerical_library() -> None:
    assert _loaded_by(["--help"]) == (0, [])


@pytest.mark.parametrize("command", ["history", "show", "select", "identify", "fk", "export", "compensate",
                                     "moveb"])
def test_a_subcommands_help_imports_none_of_the_heavy_libraries(command: str) -> None:
    rc, loaded = _loaded_by([command, "--help"])
    assert rc == 0
    heavy = set(loaded) & set(HEAVY)
    if command == "select":  # its choices come from `selector`, which stands on scipy.linalg
        heavy.discard("scipy")
    assert not heavy


def test_the_listing_says_what_the_modules_register() -> None:
    full = build_parser()
    sub = next(a for a in full._actions if isinstance(a, argparse._SubParsersAction))
    registered = [(a.dest, a.help) for a in sub._choices_actions]
    listed = [entry for name in COMMAND_MODULES for entry in COMMAND_HELP[name]]
    assert registered == listed
    lazy = build_parser(["--help"])
    sub = next(a for a in lazy._actions if isinstance(a, argparse._SubParsersAction))
    assert [(a.dest, a.help) for a in sub._choices_actions] == listed


def test_every_option_and_argument_has_help() -> None:
    missing = [f"{' '.join(path)} {'/'.join(a.option_strings) or a.dest}"
               for path, parser in _parsers(build_parser()) for a in _options(parser) if not a.help]
    assert missing == []


def test_every_default_is_shown() -> None:
    hidden = []
    for path, parser in _parsers(build_parser()):
        formatter = parser._get_formatter()
        for a in _options(parser):
            if (a.option_strings and a.default not in (None, False, [], argparse.SUPPRESS)
                    and "default" not in (formatter._get_help_string(a) or "")):
                hidden.append(f"{' '.join(path)} {a.option_strings[0]}")
    assert hidden == []
    text = " ".join(build_parser(["select"])._subparsers._group_actions[0].choices["select"]
                    .format_help().split())
    assert "(default: 20000)" in text and "(default: tabu)" in text


def test_help_speaks_of_what_the_user_does() -> None:
    for path, parser in _parsers(build_parser()):
        text = parser.format_help().lower()
        for jargon in ("seed 000", "seed 001", "method 000", "patent"):
            assert jargon not in text, f"{' '.join(path)} --help says {jargon!r}"


def test_version_is_looked_up_when_asked(capsys: pytest.CaptureFixture[str]) -> None:
    assert hil.cli.main(["--version"]) == 0
    assert capsys.readouterr().out.startswith("hil ")
