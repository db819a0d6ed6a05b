"""Robot types that disagree are refused up front by every command that drives (or simulates) an arm.

Issue 19: ``hil moveb run --sim --robot ur10e --model <ur5e model>`` drove the arm with UR10e inverse
kinematics; ``--robot ur10e --truth <ur5e truth>`` silently used the truth's robot (``hil calibrate``,
``hil sim``, ``hil tui``). Each disagreement between ``--robot``, the configuration's ``robot.type``, a
model or truth file's ``robot`` and the controller is now exit 2 with one line naming each source —
before a simulator starts, before a connection where the files already disagree, and before any motion
where only the controller can tell.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from hil.calibration.model_file import truth_document, write_json
from hil.calibration.synthetic import Noise, random_truth
from hil.cli import main
from mocks.station import simulated_serial

EXAMPLES = Path(__file__).parents[3] / "hil" / "moveb" / "examples"


def _truth(path: Path, robot: str) -> str:
    write_json(path, truth_document(random_truth(robot, np.random.default_rng(1), ideal=True), Noise()))
    return str(path)


@pytest.fixture
def no_simulator(monkeypatch: pytest.MonkeyPatch) -> list[dict]:
    """The simulated station is never started: its start is recorded and refused (exit 2)."""
    from hil.errors import InputError

    started: list[dict] = []

    def start_station(**kw: object) -> None:
        started.append(dict(kw))
        raise InputError("(test) the simulator would start here")

    monkeypatch.setattr("mocks.station.start_station", start_station)
    return started


def _error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.count("\n") == 1, err
    return err


def test_calibrate_sim_refuses_a_robot_its_truth_contradicts(tmp_path: Path, no_simulator: list[dict],
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    truth = _truth(tmp_path / "t.json", "ur5e")
    db = tmp_path / "k.db"
    assert main(["calibrate", "--sim", "--robot", "ur10e", "--truth", truth, "--db", str(db)]) == 2
    assert _error(capsys) == f"hil: error: --robot is ur10e but the truth {truth} is for ur5e\n"
    assert no_simulator == [] and not db.exists()


@pytest.mark.parametrize("robot", ["", "ur99"])
def test_an_unknown_robot_option_is_refused_naming_it(robot: str, tmp_path: Path, no_simulator: list[dict],
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["calibrate", "--sim", "--robot", robot, "--db", str(tmp_path / "k.db")]) == 2
    assert _error(capsys).startswith(f"hil: error: --robot: unknown robot {robot!r}: choose one of ")
    assert no_simulator == []


def test_calibrate_sim_without_robot_simulates_the_truths(tmp_path: Path, no_simulator: list[dict],
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    truth = _truth(tmp_path / "t.json", "ur10e")
    assert main(["calibrate", "--sim", "--truth", truth, "--db", str(tmp_path / "k.db")]) == 2
    assert [s["robot"] for s in no_simulator] == ["ur10e"]
    capsys.readouterr()


def test_calibrate_config_refuses_a_robot_option_it_contradicts(tmp_path: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    config = tmp_path / "station.toml"
    config.write_text('[robot]\ntype = "ur5e"\naddress = "127.0.0.3"\n[tracker]\nurl = "socket://127.0.0.3:1"\n')
    db = tmp_path / "k.db"
    assert main(["calibrate", "--config", str(config), "--robot", "ur10e", "--db", str(db)]) == 2
    assert _error(capsys) == f"hil: error: robot.type is ur5e in {config} but --robot is ur10e\n"


@pytest.fixture
def no_server(monkeypatch: pytest.MonkeyPatch) -> list:
    """`hil sim` never serves: the configuration it would serve is recorded instead."""
    served: list = []
    monkeypatch.setattr("mocks.ur.process.serve", lambda config, **_kw: served.append(config))
    return served


def test_sim_refuses_a_robot_its_truth_contradicts(tmp_path: Path, no_server: list,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    truth = _truth(tmp_path / "t.json", "ur5e")
    assert main(["sim", "--robot", "ur10e", "--truth", truth]) == 2
    assert _error(capsys) == f"hil: error: --robot is ur10e but the truth {truth} is for ur5e\n"
    assert no_server == []


def test_sim_simulates_and_reports_the_truths_robot(tmp_path: Path, no_server: list) -> None:
    """Without --robot the controller simulates the truth's arm (its dashboard reports the model from
    it), not a UR5e under a UR10e world."""
    truth = _truth(tmp_path / "t.json", "ur10e")
    assert main(["sim", "--truth", truth]) == 0
    assert [c.robot for c in no_server] == ["ur10e"]


def test_sim_reports_the_simulated_arms_own_serial(tmp_path: Path, no_server: list) -> None:
    """`hil sim`'s controller reports the simulated arm's serial (`mocks.station.simulated_serial`), as
    `hil calibrate --sim`'s does, not one serial for every arm; --serial still chooses one."""
    truth = _truth(tmp_path / "t.json", "ur10e")
    assert main(["sim", "--truth", truth, "--seed", "7"]) == 0
    assert main(["sim", "--seed", "7"]) == 0
    assert main(["sim", "--serial", "20235512345"]) == 0
    assert [c.serial for c in no_server] == [simulated_serial("ur10e", 7, truth), simulated_serial("ur5e", 7),
                                             "20235512345"]


@pytest.fixture
def no_app(monkeypatch: pytest.MonkeyPatch) -> list:
    """`hil tui` never opens the app: the options it would open it with are recorded instead."""
    opened: list = []

    def create_app(options: object) -> SimpleNamespace:
        opened.append(options)
        return SimpleNamespace(run=lambda: 0)

    monkeypatch.setattr("hil.tui.app.create_app", create_app)
    return opened


def test_tui_refuses_a_robot_its_truth_contradicts(tmp_path: Path, no_app: list,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    truth = _truth(tmp_path / "t.json", "ur5e")
    assert main(["tui", "--sim", "--robot", "ur10e", "--truth", truth, "--out-dir", str(tmp_path)]) == 2
    assert _error(capsys) == f"hil: error: --robot is ur10e but the truth {truth} is for ur5e\n"
    assert no_app == []
    truth = _truth(tmp_path / "t10.json", "ur10e")  # without --robot: the truth's
    assert main(["tui", "--sim", "--truth", truth, "--out-dir", str(tmp_path)]) == 0
    assert [o.robot for o in no_app] == ["ur10e"]


def test_tui_sim_keeps_its_campaigns_in_the_simulated_stations_store(
        tmp_path: Path, no_app: list, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    """`hil tui --sim` without --db opens the simulated stations' store, not $HIL_DB's (the plant's), and
    says so before the app takes the screen; --db is obeyed."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    monkeypatch.setenv("HIL_DB", str(tmp_path / "plant.db"))
    assert main(["tui", "--sim", "--out-dir", str(tmp_path)]) == 0
    sim_db = tmp_path / "data" / "hil" / "sim.db"
    assert no_app[-1].db == str(sim_db)
    assert f"hil: simulated station: its campaigns go to {sim_db}" in capsys.readouterr().err
    assert main(["tui", "--sim", "--db", str(tmp_path / "mine.db"), "--out-dir", str(tmp_path)]) == 0
    assert no_app[-1].db == str(tmp_path / "mine.db")


def test_tui_config_refuses_a_robot_option_it_contradicts(tmp_path: Path, no_app: list,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    config = tmp_path / "station.toml"
    config.write_text('[robot]\ntype = "ur5e"\n[tracker]\nurl = "socket://127.0.0.3:1"\n')
    assert main(["tui", "--config", str(config), "--robot", "ur3e", "--out-dir", str(tmp_path)]) == 2
    assert _error(capsys) == f"hil: error: robot.type is ur5e in {config} but --robot is ur3e\n"
    assert no_app == []


def test_moveb_sim_refuses_a_model_of_another_robot(tmp_path: Path, no_simulator: list[dict],
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    model = _truth(tmp_path / "m.json", "ur5e")
    program = str(EXAMPLES / "square.moveb")
    assert main(["moveb", "run", program, "--sim", "--robot", "ur10e", "--model", model]) == 2
    assert _error(capsys) == f"hil: error: --robot is ur10e but the model {model} is for ur5e\n"
    truth = _truth(tmp_path / "t.json", "ur10e")
    assert main(["moveb", "run", program, "--sim", "--truth", truth, "--model", model]) == 2
    assert _error(capsys) == f"hil: error: the model {model} is for ur5e but the truth {truth} is for ur10e\n"
    assert no_simulator == []
    # without --robot or --truth the simulator simulates the model's arm
    assert main(["moveb", "run", program, "--sim", "--model", _truth(tmp_path / "m10.json", "ur10e")]) == 2
    assert [s["robot"] for s in no_simulator] == ["ur10e"]
    capsys.readouterr()


def test_moveb_config_refuses_a_model_of_another_robot_before_connecting(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = _truth(tmp_path / "m.json", "ur10e")
    config = tmp_path / "station.toml"  # nothing listens there: a connection attempt would be exit 3
    config.write_text('[robot]\ntype = "ur5e"\naddress = "127.0.0.3"\n[tracker]\nurl = "socket://127.0.0.3:1"\n'
                      "[timeouts]\nconnect = 1.0\n")
    code = main(["moveb", "run", str(EXAMPLES / "square.moveb"), "--config", str(config), "--model", model])
    assert code == 2
    assert _error(capsys) == (f"hil: error: robot.type is ur5e in {config} but the model {model} is for "
                              "ur10e\n")


def test_moveb_config_refuses_a_controller_of_another_robot_before_any_motion(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The configuration and the model agree on a UR10e; the controller says UR5e: nothing moves."""
    from mocks.station import start_station

    model = _truth(tmp_path / "m.json", "ur10e")
    sim = start_station(robot="ur5e", speed=20.0, seed=3)
    try:
        config = tmp_path / "station.toml"
        config.write_text(f'[robot]\ntype = "ur10e"\naddress = "{sim.address}"\n'
                          f'[tracker]\nurl = "{sim.info["services"][0]["tracker_url"]}"\n')
        before = sim.state()
        out = tmp_path / "run.json"
        code = main(["moveb", "run", str(EXAMPLES / "square.moveb"), "--config", str(config), "--model",
                     model, "--frame", "current", "--out", str(out)])
        after = sim.state()
    finally:
        sim.stop()
    assert code == 2
    assert _error(capsys) == (f"hil: error: robot.type is ur10e in {config} and the model {model} is for "
                              f"ur10e but the controller at {sim.address} reports UR5e\n")
    assert after["q"] == before["q"] and not after["moving"] and not out.exists()
