"""A simulated station that does not start is a station fault (exit 3, one line), not an internal error.

Issue 19 follow-up: ``SimStartError: simulator ... did not start within 20.0 s`` (a loaded machine, ports
taken) reached the user of ``hil calibrate --sim`` as exit 70, "internal error", which tells them to
report a bug. A controller that does not boot is a hardware fault; its simulated stand-in is too.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from hil.cli import EXIT_HARDWARE, main
from mocks.ur.process import SimProcess, SimStartError


def _one_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("\n") == 1, err
    return err


EXAMPLE = str(Path(__file__).parents[3] / "hil" / "moveb" / "examples" / "square.moveb")


@pytest.mark.parametrize("command", [["calibrate", "--sim", "--speed", "20", "--db", "{tmp}/k.db"],
                                     ["moveb", "run", "--sim", "--speed", "20", EXAMPLE]],
                         ids=["calibrate", "moveb-run"])
def test_a_station_that_does_not_start_is_a_hardware_fault(
        command: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    reason = "simulator on 127.31.4.5 did not start within 20 s"

    def start_station(**_: object) -> None:
        raise SimStartError(reason)

    monkeypatch.setattr("mocks.station.start_station", start_station)
    code = main([*(a.format(tmp=tmp_path) for a in command), "--out", str(tmp_path / "r.json")])
    err = _one_line(capsys)
    assert code == EXIT_HARDWARE, err
    assert err == f"hil: hardware fault: the simulated station did not start: {reason}\n"
    assert not (tmp_path / "r.json").exists()


def test_a_real_start_timeout_is_a_hardware_fault_naming_the_timeout(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    """The real start path (child process, readiness wait) with a timeout no simulator can meet."""
    monkeypatch.setitem(SimProcess.__init__.__kwdefaults__, "start_timeout", 0.001)
    code = main(["calibrate", "--sim", "--speed", "20", "--db", str(tmp_path / "k.db"),
                 "--out", str(tmp_path / "r.json")])
    err = _one_line(capsys)
    assert code == EXIT_HARDWARE, err
    assert err.startswith("hil: hardware fault: the simulated station did not start: simulator on 127.")
    assert err.rstrip().endswith("did not start within 0.001 s"), err


def test_any_other_unexpected_error_is_still_internal(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    """Only the simulator's start failure is a station fault: a bug stays a bug (exit 70)."""

    def start_station(**_: object) -> None:
        raise RuntimeError("simulator on 127.31.4.5 did not start within 20 s")  # same text, not the type

    monkeypatch.setattr("mocks.station.start_station", start_station)
    code = main(["calibrate", "--sim", "--db", str(tmp_path / "k.db")])
    err = _one_line(capsys)
    assert code == 70 and err.startswith("hil: internal error: RuntimeError"), err
