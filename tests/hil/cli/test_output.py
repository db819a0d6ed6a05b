"""What the commands print: a closed stdout ends quietly, every written file is named on stderr (stdout
stays clean for JSON), JSON for scripts and a summary for people, and `hil select`'s progress."""

from __future__ import annotations

import io
import json
import subprocess
import sys
from pathlib import Path

import pytest

from hil.cli import main
from hil.cli.support.output import EXIT_STDOUT_CLOSED
from hil.store import Store

ROOT = Path(__file__).resolve().parents[3]
SQUARE = ROOT / "hil" / "moveb" / "examples" / "square.moveb"


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


class _ClosedPipe(io.StringIO):
    def write(self, text: str) -> int:
        raise BrokenPipeError(32, "Broken pipe")


def test_a_closed_stdout_ends_the_command_quietly(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys, "stdout", _ClosedPipe())
    code = main(["moveb", "plan", str(SQUARE), "--out", str(tmp_path / "s.csv"), "--json"])
    err = capsys.readouterr().err
    assert code == EXIT_STDOUT_CLOSED, err
    assert "error" not in err and "Traceback" not in err


def test_a_broken_pipe_elsewhere_is_still_an_error(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    import hil.moveb.path_plan

    def broken(*_args: object) -> None:
        raise BrokenPipeError(32, "Broken pipe")  # e.g. a device's socket, not the reader of stdout

    monkeypatch.setattr(hil.moveb.path_plan, "write_samples", broken)
    assert main(["moveb", "plan", str(SQUARE), "--out", str(tmp_path / "s.csv")]) == 70
    assert "BrokenPipeError" in capsys.readouterr().err


def test_show_into_a_pipe_closed_early_is_quiet_as_a_process(tmp_path: Path) -> None:
    """``hil history --json | head -0``: the reader is gone before hil writes."""
    db = tmp_path / "hil.db"
    Store.open(db).close()
    proc = subprocess.Popen([sys.executable, "-m", "hil", "history", "--json", "--db", str(db)], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()
    err = proc.stderr.read()
    assert proc.wait(timeout=120) == EXIT_STDOUT_CLOSED, err
    assert err == ""


def test_every_written_file_is_named_on_stderr(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["synth", "--ideal", "--poses", "12", "--validation", "3", "--seed", "2",
                 "--out-dir", str(tmp_path)]) == 0
    out, err = capsys.readouterr()
    assert out == "" and err.count("wrote ") == 3 and "measurements.csv (12 poses)" in err
    model = tmp_path / "model.json"
    assert main(["identify", "--robot", "ur5e", "--measurements", str(tmp_path / "measurements.csv"),
                 "--out", str(model), "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["poses"] == 12 and f"wrote {model}" in err
    for argv, path in (
            (["export", "--model", str(model), "--format", "urdf"], tmp_path / "m.urdf"),
            (["fk", "--model", str(model), "--joints", str(tmp_path / "validation.csv")], tmp_path / "p.csv"),
            (["moveb", "plan", str(SQUARE)], tmp_path / "s.csv"),
            (["select", "--robot", "ur5e", "--count", "12", "--candidates", "1500", "--no-bound"],
             tmp_path / "poses.json")):
        assert main([*argv, "--out", str(path)]) == 0
        out, err = capsys.readouterr()
        assert path.exists() and f"wrote {path}" in err, argv
        if argv[0] in ("export", "fk", "select"):
            assert out == "", argv


def test_moveb_plan_prints_json_to_scripts_and_a_summary_to_people(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    argv = ["moveb", "plan", str(SQUARE), "--out", str(tmp_path / "s.csv")]
    assert main(argv) == 0  # captured stdout is not a terminal: JSON, as scripts have always read
    assert json.loads(capsys.readouterr().out)["points"] == 6
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stdout", terminal)
    assert main(argv) == 0
    text = terminal.getvalue()
    assert "6 points" in text and "cycle time" in text and "{" not in text
    terminal.seek(0)
    terminal.truncate()
    assert main([*argv, "--json"]) == 0
    assert json.loads(terminal.getvalue())["points"] == 6


def test_sim_ready_line_reads_well_on_a_terminal() -> None:
    from hil.cli.sim import _summary

    info = {"robot": {"address": "127.0.0.9", "rtde_port": 30004, "dashboard_port": 29999,
                      "script_port": 30003, "control_port": 30999},
            "tracker": {"url": "socket://127.0.0.9:4000", "pty": "/dev/pts/7",
                        "emscon_url": "tcp://127.0.0.9:700"}, "truth": {"joints": [[0.123456789] * 3]}}
    text = _summary(info)
    assert "127.0.0.9" in text and "socket://127.0.0.9:4000" in text and "tcp://127.0.0.9:700" in text
    assert "0.123456789" not in text and "Ctrl-C" in text


def test_select_shows_progress_on_a_terminal_and_can_skip_the_bound(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    out = tmp_path / "poses.json"
    argv = ["select", "--robot", "ur5e", "--count", "12", "--candidates", "1500", "--out", str(out)]
    assert main(argv) == 0
    shown = terminal.getvalue()
    assert "1500 found" in shown and "restart 12/12" in shown and "bound: O1 <=" in shown
    assert json.loads(out.read_text())["bound"] > 0
    terminal.seek(0)
    terminal.truncate()
    assert main([*argv, "--no-bound"]) == 0
    doc = json.loads(out.read_text())
    assert doc["bound"] is None and doc["percent_of_bound"] is None and doc["value"] > 0
    assert "bound:" not in terminal.getvalue()
    terminal.seek(0)
    terminal.truncate()
    assert main([*argv, "--quiet"]) == 0
    assert terminal.getvalue().startswith("wrote ")


def test_a_missing_stdout_is_found_before_the_work(monkeypatch) -> None:
    """``hil select >&-`` searched for seconds and only then failed to write (issue 31)."""
    from hil.cli.support.output import StdoutUnwritable, check_stdout_open, quiet_on_closed_stdout

    worked = []

    def command(_args) -> int:
        check_stdout_open()
        worked.append(True)
        return 0

    monkeypatch.setattr(sys, "stdout", None)
    with pytest.raises(StdoutUnwritable, match="stdout is closed"):
        quiet_on_closed_stdout(command)(None)
    assert worked == []
    monkeypatch.setattr(sys, "stdout", io.StringIO())
    assert quiet_on_closed_stdout(command)(None) == 0 and worked == [True]


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full on this system")
def test_stdout_on_dev_full_is_found_before_the_work(monkeypatch) -> None:
    """``hil select > /dev/full`` searched for 2.5-3.7 s (loaded machine) before its write failed: the
    one device known to refuse every write is named before the search; /dev/null still takes output."""
    from hil.cli.support.output import StdoutUnwritable, check_stdout_open

    with open("/dev/full", "w") as full, open("/dev/null", "w") as null:
        monkeypatch.setattr(sys, "stdout", full)
        with pytest.raises(StdoutUnwritable, match="No space left on device"):
            check_stdout_open()
        monkeypatch.setattr(sys, "stdout", null)
        check_stdout_open()


def test_every_command_is_refused_before_it_runs_when_stdout_is_unusable(monkeypatch, tmp_path) -> None:
    """``hil identify > /dev/full`` wrote its model and then failed on stdout (issue 31, second pass):
    the wrapper every subcommand runs in checks stdout first, whether or not the command asks."""
    from hil.cli import main
    from hil.cli.support.output import StdoutUnwritable, quiet_on_closed_stdout

    worked = []
    monkeypatch.setattr(sys, "stdout", None)
    with pytest.raises(StdoutUnwritable, match="stdout is closed"):
        quiet_on_closed_stdout(lambda _args: worked.append(True))(None)
    assert worked == []
    model = tmp_path / "m.json"
    assert main(["identify", "--robot", "ur5e", "--measurements", str(tmp_path / "none.csv"),
                 "--out", str(model)]) == 2  # refused for stdout before the missing file is looked at
    assert not model.exists()
