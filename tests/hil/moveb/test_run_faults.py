"""Issue 19 (smaller): a hardware fault during `hil moveb run` says so on stderr, one line, exit 3.

It used to print nothing on stderr (only the result document on stdout carried the error), so a script
or an operator reading the terminal's error stream saw a silent exit 3. Here on the simulated station,
with a protective stop (robot) or an unplugged tracker injected once the arm is seen moving.
"""

from __future__ import annotations

import contextlib
import json
import threading
import time

import pytest

import hil.station.simulated
from hil.cli import main

# A short program (two straight moves, one corner): little to plan, over in a second.
PROGRAM = ("MOVEB 0 0 0 0 0 1 1 0 0 0.5 0.2\nMOVEB 60 0 0 0 0 1 1 0 0 0.5 0.2\n"
           "MOVEB 60 60 0 0 0 1 1 0 0 0.5 0.2\n")


def _inject_once_moving(monkeypatch: pytest.MonkeyPatch, fault: str) -> list[str]:
    """Make the simulated station inject `fault` as soon as its arm moves; returns what was injected."""
    real = hil.station.simulated.simulated_station
    injected: list[str] = []

    @contextlib.contextmanager
    def station(*args, **kwargs):  # type: ignore[no-untyped-def]
        with real(*args, **kwargs) as (config, identity, truth, sim):
            done = threading.Event()

            def watch() -> None:
                while not done.is_set():
                    if sim.state()["moving"]:
                        sim.inject(fault)
                        injected.append(fault)
                        return
                    time.sleep(0.005)

            thread = threading.Thread(target=watch, daemon=True)
            thread.start()
            try:
                yield config, identity, truth, sim
            finally:
                done.set()
                thread.join(5)

    monkeypatch.setattr(hil.station.simulated, "simulated_station", station)
    return injected


@pytest.mark.parametrize(("fault", "names"), [("protective_stop", "protective"),
                                               ("tracker_unplug", "Tracker")])
def test_a_hardware_fault_is_one_line_on_stderr_and_exit_3(tmp_path, capsys, monkeypatch, fault, names):
    injected = _inject_once_moving(monkeypatch, fault)
    out = tmp_path / "run.json"
    program = tmp_path / "short.moveb"
    program.write_text(PROGRAM)
    code = main(["moveb", "run", str(program), "--sim", "--ideal", "--speed", "5",
                 "--out", str(out), "--json"])
    captured = capsys.readouterr()
    assert code == 3, captured.err
    assert injected == [fault]
    lines = captured.err.splitlines()
    faults = [line for line in lines if line.startswith("hil: hardware fault: ")]
    assert len(faults) == 1, captured.err
    assert names.lower() in faults[0].lower() and "Traceback" not in captured.err
    doc = json.loads(captured.out)
    assert doc["status"] == "hardware fault" and doc["exit_code"] == 3
    assert doc == json.loads(out.read_text())  # the document still says what happened
