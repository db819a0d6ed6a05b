"""`hil compensate` end to end: a truth with a controller block, a CSV and a program in, compensated
files out that land on the targets; bad input is one line, exit 2, and no file; a controller that does
not answer is a station fault (exit 3)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from hil.arm.controller_model import ControllerCalibration
from hil.calibration.model_file import load_geometry
from hil.cli import main
from hil.compensation.poses import CANONICAL_NEAR, to_se3, to_vector
from hil.compensation.solve import Compensator
from tests.hil.compensation.world import assert_lands, random_controller


@pytest.fixture(scope="module")
def station(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A simulator truth that carries its controller's calibration, and targets made on it."""
    out = tmp_path_factory.mktemp("compensate")
    assert main(["synth", "--robot", "ur5e", "--poses", "5", "--validation", "2", "--seed", "8", "--rigid",
                 "--out-dir", str(out)]) == 0
    doc = json.loads((out / "truth.json").read_text())
    doc["controller"] = random_controller(np.random.default_rng(8)).to_dict()
    (out / "truth.json").write_text(json.dumps(doc))
    comp = _compensator(out)
    rng = np.random.default_rng(9)
    Q = np.asarray(CANONICAL_NEAR) + rng.uniform(-0.4, 0.4, (6, 6))
    np.save(out / "q.npy", Q)
    rows = [",".join([*(repr(float(v)) for v in to_vector(comp.accurate_pose(q))),
                      *(repr(float(v)) for v in q), f"part {i}"]) for i, q in enumerate(Q)]
    (out / "poses.csv").write_text("x,y,z,rx,ry,rz,q1,q2,q3,q4,q5,q6,label\n" + "\n".join(rows) + "\n")
    literal = "p[" + ", ".join(repr(float(v)) for v in to_vector(comp.accurate_pose(Q[1]))) + "]"
    (out / "prog.script").write_text(
        "def prog():\n"
        f"  movej([{', '.join(repr(float(v)) for v in Q[1])}])\n"
        f"  movel({literal}, a=1.2, v=0.25)  # the one target\n"
        "  movel(pose_trans(get_actual_tcp_pose(), p[0, 0, .01, 0, 0, 0]))\n"
        "end\n")
    return out


def _compensator(d: Path) -> Compensator:
    geometry, doc = load_geometry(d / "truth.json")
    return Compensator(geometry, ControllerCalibration.from_dict(doc["controller"]).geometry("ur5e"))


def test_a_csv_end_to_end(station: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "commands.csv"
    truth = str(station / "truth.json")
    assert main(["compensate", "--model", truth, "--controller", truth, str(station / "poses.csv"),
                 "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "6 targets compensated: shift mean" in err and "wrote" in err
    comp, Q = _compensator(station), np.load(station / "q.npy")
    lines = out.read_text().splitlines()
    assert lines[0] == "x,y,z,rx,ry,rz,q1,q2,q3,q4,q5,q6,label"
    for q, line in zip(Q, lines[1:], strict=True):
        cells = line.split(",")
        assert_lands(comp, to_se3([float(v) for v in cells[:6]]), q, comp.accurate_pose(q))
        assert cells[-1].startswith("part ")


def test_a_program_end_to_end_with_json(station: Path, tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "prog.script"
    truth = str(station / "truth.json")
    assert main(["compensate", "--model", truth, "--controller", truth, str(station / "prog.script"),
                 "--out", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["kind"] == "urscript" and doc["compensated"] == 1 and doc["not_compensated_count"] == 1
    assert doc["not_compensated"][0]["line"] == 4 and doc["targets"][0]["line"] == 3
    assert 0 < doc["shift_mm"]["max"] < 50
    original, written = (station / "prog.script").read_text().splitlines(), out.read_text().splitlines()
    assert [a == b for a, b in zip(original, written, strict=True)] == [True, True, False, True, True]
    comp, Q = _compensator(station), np.load(station / "q.npy")
    literal = written[2][written[2].index("p[") + 2:written[2].index("]")]
    assert_lands(comp, to_se3([float(v) for v in literal.split(",")]), Q[1], comp.accurate_pose(Q[1]))


def test_joints_from_the_command_line(station: Path, tmp_path: Path) -> None:
    out = tmp_path / "joints.csv"
    truth = str(station / "truth.json")
    assert main(["compensate", "--model", truth, "--controller", truth, str(station / "poses.csv"),
                 "--out", str(out), "--joints"]) == 0
    assert out.read_text().splitlines()[0] == "q1,q2,q3,q4,q5,q6,label"


def _controller_file(d: Path, robot: str = "ur5e", drop: str | None = None) -> str:
    block = random_controller(np.random.default_rng(1)).to_dict()
    if drop:
        del block[drop]
    (d / "k.json").write_text(json.dumps({"robot": robot, "controller": block}))
    return str(d / "k.json")


BAD = [  # (controller file: robot, dropped field; INPUT: name and text, None: the good CSV; options; says)
    (("ur10e", None), None, [],
     "k.json: robot: the controller's calibration is of a 'ur10e', the model of a 'ur5e'"),
    (("ur5e", "delta_d"), None, [], "k.json: controller: missing field 'delta_d'"),
    (None, None, [], "measurements.csv"),  # --controller names a file that is not JSON
    (("ur5e", None), ("bad.script", "movel(p[.4, 0, .3, 3, 0)\n"), [], "bad.script:1: ')' closes the '['"),
    (("ur5e", None), ("five.script", "\n\nmovel(p[.4, 0, .3, 3, 0])\n"), [],
     "five.script:3: movel: p[...] has 5 elements"),
    (("ur5e", None), ("far.csv", "x,y,z,rx,ry,rz\n2.5,0,.3,3.1,0,0\n"), [], "far.csv: line 2: "),
    (("ur5e", None), ("far.urscript", "#\nmovej(p[0, 0, 2, 0, 0, 0])\n"), [], "far.urscript:2: movej: "),
    (("ur5e", None), None, ["--near", "0,0,9,0,0,0"], "--near: q3 = 9 rad is outside the joint limits"),
    (("ur5e", None), None, ["--tcp", "0,0,100,0,0,0"], "--tcp: "),
    (("ur5e", None), ("prog.urp", "<urp/>"), [], "prog.urp: a Polyscope"),
]


@pytest.mark.parametrize(("controller", "program", "options", "says"), BAD, ids=[b[3][:24] for b in BAD])
def test_bad_input_is_one_line_and_writes_nothing(controller, program, options, says: str, station: Path,
                                                  tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    k = _controller_file(tmp_path, *controller) if controller else str(station / "measurements.csv")
    given = _write(tmp_path / program[0], program[1]) if program else str(station / "poses.csv")
    out = tmp_path / "out.txt"
    code = main(["compensate", "--model", str(station / "truth.json"), "--controller", k, given, *options,
                 "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert says in err
    assert not out.exists()


def _write(path: Path, text: str) -> str:
    path.write_text(text)
    return str(path)


def test_the_model_and_the_configuration_must_name_one_robot(station: Path, tmp_path: Path,
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    config = _write(tmp_path / "station.toml", '[robot]\ntype = "ur10e"\naddress = "127.0.0.1"\n')
    out = tmp_path / "o.csv"
    assert main(["compensate", "--model", str(station / "truth.json"), "--config", config,
                 str(station / "poses.csv"), "--out", str(out)]) == 2
    assert "robot.type is 'ur10e'" in capsys.readouterr().err
    assert not out.exists()


def test_a_controller_that_does_not_answer_is_a_station_fault(station: Path, tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("drivers.robot.kinematics_info", reason="the KinematicsInfo reader (issue 14, H1)")
    from mocks.ur.testing import random_loopback

    address = random_loopback()  # nothing listens there
    config = _write(tmp_path / "station.toml",
                    f'[robot]\ntype = "ur5e"\naddress = "{address}"\n[timeouts]\nconnect = 2.0\n')
    out = tmp_path / "o.csv"
    assert main(["compensate", "--model", str(station / "truth.json"), "--config", config,
                 str(station / "poses.csv"), "--out", str(out)]) == 3
    err = capsys.readouterr().err
    assert address in err and "hil: fault:" in err
    assert not out.exists()


def test_the_calibration_read_from_a_simulated_controller(station: Path, tmp_path: Path) -> None:
    """--config reads the KinematicsInfo the (simulated) controller publishes on port 30001: the same
    compensation as the controller block given as a file."""
    pytest.importorskip("drivers.robot.kinematics_info", reason="the KinematicsInfo reader (issue 14, H1)")
    from mocks.ur.controller import SimConfig
    from mocks.ur.testing import start_sim

    block = json.loads((station / "truth.json").read_text())["controller"]
    sim = start_sim(SimConfig(robot="ur5e", controller=block))
    try:
        config = _write(tmp_path / "station.toml", f'[robot]\ntype = "ur5e"\naddress = "{sim.address}"\n')
        live, from_file = tmp_path / "live.csv", tmp_path / "file.csv"
        truth = str(station / "truth.json")
        assert main(["compensate", "--model", truth, "--config", config, str(station / "poses.csv"),
                     "--out", str(live)]) == 0
    finally:
        sim.stop()
    assert main(["compensate", "--model", truth, "--controller", truth, str(station / "poses.csv"),
                 "--out", str(from_file)]) == 0
    a = np.loadtxt(live, delimiter=",", skiprows=1, usecols=range(6))
    b = np.loadtxt(from_file, delimiter=",", skiprows=1, usecols=range(6))
    assert np.abs(a - b).max() < 1e-9  # KinematicsInfo carries the DH table as doubles
