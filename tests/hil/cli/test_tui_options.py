"""`hil tui`'s options reach the app as `TuiOptions` (the app itself is not opened)."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import pytest

from hil.cli import main


@pytest.fixture
def no_app(monkeypatch: pytest.MonkeyPatch) -> list:
    """`hil tui` never opens the app: the options it would open it with are recorded instead."""
    opened: list = []

    def create_app(options: object) -> SimpleNamespace:
        opened.append(options)
        return SimpleNamespace(run=lambda: 0)

    monkeypatch.setattr("hil.tui.app.create_app", create_app)
    return opened


def test_no_warmup_is_parsed_as_hil_calibrates(tmp_path: Path, no_app: list) -> None:
    """Issue 29 (item 16): a quick look from the TUI skips the warm-up, as `hil calibrate --no-warmup`."""
    db = str(tmp_path / "sim.db")
    assert main(["tui", "--sim", "--db", db, "--out-dir", str(tmp_path)]) == 0
    assert main(["tui", "--sim", "--no-warmup", "--db", db, "--out-dir", str(tmp_path)]) == 0
    config = tmp_path / "station.toml"
    config.write_text('[robot]\ntype = "ur5e"\n[tracker]\nurl = "socket://127.0.0.3:1"\n')
    assert main(["tui", "--config", str(config), "--no-warmup", "--db", db, "--out-dir", str(tmp_path)]) == 0
    assert [o.no_warmup for o in no_app] == [False, True, True]
    assert no_app[2].config is not None


def test_the_app_without_a_terminal_is_refused_in_one_line(tmp_path: Path) -> None:
    """Started with its input and output redirected, `hil tui` used to take the screen of no terminal
    and wait for ever; it is refused before anything opens, exit 2."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "hil", "tui", "--sim", "--db", str(tmp_path / "s.db")],
                          stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=60,
                          cwd=Path(__file__).resolve().parents[3])
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        "hil: error: hil tui needs a terminal, and its standard input and standard output are not one: "
        "run it in a terminal (ssh -t), or use hil calibrate, the headless command"]
    assert not (tmp_path / "s.db").exists()  # nothing opened
