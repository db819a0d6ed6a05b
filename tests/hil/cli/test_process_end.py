"""`hil tui` ends its process once the app has closed: the atexit handlers and the streams' flush run,
the interpreter's teardown does not (`hil.cli.support.process_end`)."""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import pytest

from hil.cli import tui

ROOT = Path(__file__).resolve().parents[3]


def test_the_process_ends_with_its_code_after_the_exit_handlers_and_the_flush() -> None:
    code = ("import atexit, sys\n"
            "from hil.cli.support.process_end import end_process\n"
            "class Noisy:\n"
            "    def __del__(self):\n"
            "        print('teardown ran', flush=True)\n"
            "keep = Noisy()\n"  # a module global: only the interpreter's teardown would free it
            "atexit.register(lambda: print('atexit ran'))\n"
            "print('buffered', end='')\n"
            "sys.stderr.write('on stderr')\n"
            "end_process(7)\n"
            "print('never')\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert out.returncode == 7
    assert out.stdout == "bufferedatexit ran\n"
    assert out.stderr == "on stderr"


def test_the_tui_command_ends_the_process_once_the_app_has_closed(monkeypatch: pytest.MonkeyPatch) -> None:
    ran, ended = [], []

    class App:
        def run(self) -> int:
            ran.append(True)
            return 130

    def end(code: int) -> None:
        ended.append(code)
        raise SystemExit(code)

    monkeypatch.setattr(tui, "options_from", lambda args: object())
    monkeypatch.setattr(tui, "check_store", lambda db, config: None)
    monkeypatch.setattr(tui, "require_terminal", lambda: None)  # a test has none; tested on its own
    monkeypatch.setattr("hil.tui.app.create_app", lambda options: App())
    monkeypatch.setattr("hil.cli.support.process_end.end_process", end)
    with pytest.raises(SystemExit):
        tui.run(argparse.Namespace(as_program=True))  # the hil program (hil.cli.main without argv)
    assert ran == [True] and ended == [130]
    # called in-process (hil.cli.main with an argument list: a test, a script) it returns the code
    assert tui.run(argparse.Namespace(as_program=False)) == 130
    assert ran == [True, True] and ended == [130]
