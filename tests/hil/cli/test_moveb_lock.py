"""Issue 19 follow-up, "the leases everywhere the arm is driven": `hil moveb run` takes the arm's host-local
address lock (`hil.store.address_lock`, the one `hil calibrate` and the TUI take) before connecting.

Before, it connected and drove the arm whatever else did: a `hil calibrate` measuring on the same arm
would have had its control script replaced mid-campaign. Now a held lock is refused in one line (exit 2,
naming the holder) before the robot is connected, the lock is held while the program runs (so a
campaign started meanwhile is refused in turn), and it is free again once the run has ended.
"""

from __future__ import annotations

import contextlib
import json
import os
import threading
import time
from pathlib import Path

import pytest

import hil.station.devices
import hil.station.simulated
from drivers.robot.errors import RobotUnreachable
from hil.cli import main
from hil.store import LeaseRefused, address_lock

# A short program (two straight moves, one corner): little to plan, over in a second.
PROGRAM = ("MOVEB 0 0 0 0 0 1 1 0 0 0.5 0.2\nMOVEB 60 0 0 0 0 1 1 0 0 0.5 0.2\n"
           "MOVEB 60 60 0 0 0 1 1 0 0 0.5 0.2\n")
ADDRESS = "127.0.0.42"


def _program(tmp_path: Path) -> Path:
    program = tmp_path / "short.moveb"
    program.write_text(PROGRAM)
    return program


def _config(tmp_path: Path) -> Path:
    config = tmp_path / "station.toml"
    config.write_text(f'[station]\nname = "cell-9"\n[robot]\naddress = "{ADDRESS}"\n'
                      '[tracker]\nurl = "/dev/ttyFAKE"\nposition = [2.0, 0.5, 0.3]\n'
                      "[keep_in]\nmin = [-2.0, -2.0, -0.5]\nmax = [2.0, 2.0, 2.0]\n")
    return config


def _connects(monkeypatch: pytest.MonkeyPatch, then=None) -> list[object]:
    """A tripwire on the station's connect — its first connection, the controller asked what it is
    (`hil.station.devices.ask_controller`, before the devices open): records each call (its config),
    then calls `then` (None: nothing answers)."""
    calls: list[object] = []

    def ask_controller(config):  # type: ignore[no-untyped-def]
        calls.append(config)
        if then is None:
            raise RobotUnreachable(f"no controller at {config.robot['address']} (test)")
        return then(config)

    monkeypatch.setattr(hil.station.devices, "ask_controller", ask_controller)
    return calls


def _error_line(err: str) -> str:
    (line,) = err.splitlines()
    return line


def test_config_an_arm_another_process_drives_is_refused_before_connecting(tmp_path, monkeypatch, capsys):
    connects = _connects(monkeypatch)
    command = ["moveb", "run", str(_program(tmp_path)), "--config", str(_config(tmp_path)), "--json"]
    with address_lock(ADDRESS, what="hil calibrate"):
        assert main(command) == 2
    captured = capsys.readouterr()
    line = _error_line(captured.err)
    assert line.startswith(f"hil: error: the robot at {ADDRESS} is in use by hil calibrate "
                           f"(pid {os.getpid()} "), line
    assert "wait for it to end, or stop it" in line
    assert connects == [] and captured.out == ""  # never connected, no result document

    # once released the command connects (here to a controller that does not answer: exit 3)
    assert main(command) == 3
    captured = capsys.readouterr()
    assert len(connects) == 1 and connects[0].robot["address"] == ADDRESS
    assert "hil: hardware fault: RobotUnreachable: no controller at 127.0.0.42" in captured.err
    with address_lock(ADDRESS):  # and the lock is free again after a failed connect
        pass


def test_sim_the_lock_refuses_a_run_is_held_while_it_runs_and_freed_after(tmp_path, monkeypatch, capsys):
    """On the simulated station (its address is random: read from the station the command starts)."""
    real_station = hil.station.simulated.simulated_station
    connects = _connects(monkeypatch, then=hil.station.devices.ask_controller)
    hold = {"lock": True}
    seen: dict[str, object] = {}

    @contextlib.contextmanager
    def station(*args, **kwargs):  # type: ignore[no-untyped-def]
        with real_station(*args, **kwargs) as (config, identity, truth, sim):
            address = seen["address"] = config.robot["address"]
            if hold["lock"]:  # another process (a `hil calibrate`) drives this arm
                with address_lock(address, what="hil calibrate"):
                    yield config, identity, truth, sim
                return
            done = threading.Event()

            def watch() -> None:  # while the arm moves, a second driver of the arm is refused
                while not done.is_set():
                    if sim.state()["moving"]:
                        try:
                            with address_lock(address, what="hil calibrate"):
                                seen["meanwhile"] = "acquired"
                        except LeaseRefused as exc:
                            seen["meanwhile"] = str(exc)
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
    command = ["moveb", "run", str(_program(tmp_path)), "--sim", "--ideal", "--speed", "10", "--json"]

    assert main(command) == 2
    captured = capsys.readouterr()
    line = _error_line(captured.err)
    assert line.startswith(f"hil: error: the robot at {seen['address']} is in use by hil calibrate "), line
    assert connects == [] and captured.out == ""

    hold["lock"] = False
    code = main(command)
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert json.loads(captured.out)["status"] == "done"
    assert len(connects) == 1
    assert str(seen.get("meanwhile", "")).startswith(f"the robot at {seen['address']} is in use by "
                                                     f"hil moveb run (pid {os.getpid()} "), seen
    with address_lock(str(seen["address"])):  # released once the run has ended
        pass
