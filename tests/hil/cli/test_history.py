"""`hil history` and `hil show`: listing, printing, exporting by campaign id, and bad input (exit 2,
one line, no traceback, no database created)."""

from __future__ import annotations

import json
import sqlite3
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hil.arm.geometry import Geometry
from hil.calibration.measurements import read_measurements
from hil.calibration.model_file import MODEL_FORMAT, load_geometry
from hil.campaign.events import ModelIdentified, PointMeasured, RunFinished, RunStarted, ValidationDone
from hil.cli import main
from hil.station.config import default_config
from hil.store import SCHEMA_VERSION, RobotIdentity, Store

ROOT = Path(__file__).resolve().parents[3]


def model_doc() -> dict:
    return {"format": MODEL_FORMAT, **Geometry.nominal("ur5e").to_dict(),
            "parameters": [{"name": "p", "value": 0.0, "std": 1e-6}] * 27,
            "fit": {"rms": 18e-6, "max": 45e-6, "iterations": 6, "rejected": []},
            "input": {"file": "campaign", "sha256": "0" * 64}}


@pytest.fixture
def db(tmp_path) -> Path:
    """A database with a finished campaign (latest) and an interrupted one."""
    path = tmp_path / "hil.db"
    config = default_config().as_dict()
    config["station"]["name"] = "eol-cell-3"
    with Store.open(path) as s:
        old = s.create_campaign(config, RobotIdentity("ur5e", "2023550001", "UR5e", "5.15"), now=1.7e9)
        s.save_plan(old, [(i, "calibration", [0.1 * i] * 6) for i in range(4)])
        s.record_measurement(old, 0, "calibration", [0.0] * 6, [1, 2, 3], t=1.7e9 + 1)
        s.set_status(old, "running")
        cid = s.create_campaign(config, RobotIdentity("ur5e", "2023550002"), {"method": "tabu"},
                                now=1.7e9 + 100)
        s.save_plan(cid, [(i, "calibration" if i < 3 else "validation", [0.1 * i] * 6)
                          for i in range(5)])
        s.record_event(RunStarted(campaign=cid, robot="ur5e", station="eol-cell-3", poses=5))
        for i in range(5):
            s.record_event(PointMeasured(campaign=cid, index=i, role="calibration" if i < 3
                                         else "validation", q=[0.1 * i] * 6, p=[1.0, 2.0, i],
                                         p_spread=[0] * 3, samples=5))
        s.record_event(ModelIdentified(campaign=cid, rms=18e-6, max=45e-6, iterations=6,
                                       rejected=[], model=model_doc()))
        s.record_event(ValidationDone(campaign=cid, before={"count": 2, "rms": 1.8e-3, "max": 2e-3},
                                      after={"count": 2, "rms": 21e-6, "max": 40e-6}, passed=True))
        s.record_event(RunFinished(campaign=cid, status="accepted"))
    return path


def ids(path: Path) -> list[str]:
    with Store.open(path) as s:
        return [c.id for c in s.campaigns()]


def run_bad(capsys, argv) -> str:
    code = main(argv)
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert captured.out == ""
    return err


def test_history_text_and_json(db, capsys):
    new, old = ids(db)
    assert main(["history", "--db", str(db)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split()[:3] == ["ID", "UPDATED", "STATION"]
    assert lines[1].startswith(new) and "accepted" in lines[1] and "5/5" in lines[1]
    assert lines[1].endswith(" 0.021")
    assert lines[2].startswith(old) and "running" in lines[2] and "1/4" in lines[2]
    assert all(len(line) < 80 for line in lines)  # the 80x24 terminal
    assert main(["history", "--db", str(db), "--json", "--limit", "1"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["database"] == str(db)
    [row] = doc["campaigns"]
    assert row["id"] == new and row["validation_rms"] == 21e-6 and row["measured"] == 5
    assert row["station"] == "eol-cell-3" and row["serial"] == "2023550002" and row["passed"] is True
    assert main(["history", "--db", str(db), "--station", "elsewhere"]) == 0
    assert "no campaigns" in capsys.readouterr().out


def test_history_says_which_database_it_reads(db, capsys, monkeypatch):
    """One line on stderr names the database (absolute), so stdout stays the table; the JSON has it."""
    monkeypatch.chdir(db.parent)
    assert main(["history", "--db", db.name]) == 0
    captured = capsys.readouterr()
    assert captured.err.strip().splitlines() == [f"database: {db.resolve()}"]
    assert captured.out.splitlines()[0].startswith("ID ") and str(db) not in captured.out
    assert main(["history", "--db", db.name, "--station", "elsewhere"]) == 0
    assert capsys.readouterr().err.strip() == f"database: {db.resolve()}"
    assert main(["history", "--db", db.name, "--json"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["database"] == db.name and captured.err == ""


def test_a_campaign_whose_process_died_is_interrupted_and_resumable(db, capsys, monkeypatch):
    """`running` in the file, but the process that ran it is gone (kill -9, power cut)."""
    from hil.store import owner

    gone = subprocess.Popen(["true"])
    gone.wait()
    monkeypatch.setattr("hil.store.recorder.this_process", lambda: {**owner.this_process(), "pid": gone.pid})
    with Store.open(db) as s:
        cid = s.create_campaign(default_config().as_dict(), RobotIdentity("ur5e", "2023550003"),
                                now=1.7e9 + 200)
        s.save_plan(cid, [(i, "calibration", [0.1 * i] * 6) for i in range(4)])
        s.record_event(RunStarted(campaign=cid, robot="ur5e", station="station", poses=4))
        s.record_event(PointMeasured(campaign=cid, index=0, role="calibration", q=[0.0] * 6,
                                     p=[1.0, 2.0, 3.0], p_spread=[0] * 3, samples=5))
    assert main(["history", "--db", str(db)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[1].startswith(cid) and " interrupted " in lines[1] and "1/4" in lines[1]
    assert lines[-1].startswith("interrupted (resumable): re-run the same `hil calibrate` command")
    assert "running" in lines[3]  # an older hil's run (no owner recorded): cannot tell, as it was
    assert all(len(line) < 80 for line in lines)
    assert main(["show", cid, "--db", str(db)]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"campaign {cid}: interrupted (resumable) — its process ended")
    assert main(["history", "--db", str(db), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["campaigns"][0]["status"] == "interrupted"


def test_history_uses_hil_db_and_config(db, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("HIL_DB", str(db))
    assert main(["history", "--json"]) == 0
    assert len(json.loads(capsys.readouterr().out)["campaigns"]) == 2
    monkeypatch.delenv("HIL_DB")
    station = tmp_path / "station.toml"
    station.write_text(f'[store]\npath = "{db.name}"\n')
    assert main(["history", "--config", str(station), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["database"] == str(db)


def test_show_text_and_json(db, capsys):
    new, old = ids(db)
    assert main(["show", new[:15], "--db", str(db)]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"campaign {new}: accepted")
    for text in ("eol-cell-3", "serial 2023550002", "method tabu", "3 calibration, 2 validation",
                 "5 measured", "RMS 0.018 mm", "27 parameters", "1.800 mm before -> 0.021 mm after",
                 "passed", "PointMeasured 5"):
        assert text in out, text
    assert main(["show", "last", "--db", str(db), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["summary"]["id"] == new and len(doc["measurements"]) == 5
    assert doc["models"][0]["doc"]["format"] == MODEL_FORMAT
    assert doc["config"]["station"]["name"] == "eol-cell-3"
    assert main(["show", old, "--db", str(db)]) == 0
    out = capsys.readouterr().out
    assert "running" in out and "model       none yet" in out and "3 pending" in out


def test_show_exports(db, tmp_path, capsys):
    new, _ = ids(db)
    model = tmp_path / "out" / "model.json"
    model.parent.mkdir()  # an output's folder must exist (a missing one is refused: a typo, likely)
    assert main(["show", new, "--db", str(db), "--export-model", str(model)]) == 0
    geometry, doc = load_geometry(model, (MODEL_FORMAT,))
    assert doc == model_doc() and geometry.robot == "ur5e"
    urdf, yaml_ = tmp_path / "robot.urdf", tmp_path / "kin.txt"
    assert main(["show", new, "--db", str(db), "--export-model", str(urdf)]) == 0
    assert "<robot" in urdf.read_text()
    assert main(["show", new, "--db", str(db), "--export-model", str(yaml_),
                 "--format", "ros-kinematics"]) == 0
    assert "kinematics:" in yaml_.read_text()
    csv = tmp_path / "val.csv"
    assert main(["show", new, "--db", str(db), "--export-measurements", str(csv), "--role",
                 "validation"]) == 0
    meas = read_measurements(csv)
    np.testing.assert_array_equal(meas.p, [[1.0, 2.0, 3.0], [1.0, 2.0, 4.0]])
    assert "wrote" in capsys.readouterr().err


def test_bad_input(db, tmp_path, capsys):
    new, old = ids(db)
    missing = tmp_path / "nowhere" / "hil.db"
    err = run_bad(capsys, ["history", "--db", str(missing)])
    assert "no such database" in err and str(missing) in err
    assert not missing.parent.exists()  # reading never creates a database
    run_bad(capsys, ["show", new, "--db", str(missing)])
    junk = tmp_path / "junk.db"
    junk.write_text("not a database\n" * 200)
    assert "not a hil database" in run_bad(capsys, ["history", "--db", str(junk)])
    assert "not a hil database" in run_bad(capsys, ["show", "x", "--db", str(junk)])
    other = tmp_path / "other.db"
    conn = sqlite3.connect(other)
    conn.execute("CREATE TABLE t (x)")
    conn.close()
    assert "not a hil store" in run_bad(capsys, ["history", "--db", str(other)])
    assert "no campaign 'nope'" in run_bad(capsys, ["show", "nope", "--db", str(db)])
    assert "several" in run_bad(capsys, ["show", new[:4], "--db", str(db)])
    err = run_bad(capsys, ["show", old, "--db", str(db), "--export-model", str(tmp_path / "m.json")])
    assert "no calibrated model" in err and not (tmp_path / "m.json").exists()
    assert "no validation measurements" in run_bad(
        capsys, ["show", old, "--db", str(db), "--export-measurements", str(tmp_path / "v.csv"),
                 "--role", "validation"])
    assert "--format" in run_bad(capsys, ["show", new, "--db", str(db), "--format", "urdf"])
    assert "--limit" in run_bad(capsys, ["history", "--db", str(db), "--limit", "0"])
    run_bad(capsys, ["history", "--db", str(db), "--limit", "many"])
    run_bad(capsys, ["show", "--db", str(db)])
    newer = tmp_path / "newer.db"
    Store.open(newer).close()
    conn = sqlite3.connect(newer)
    conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 3}")
    conn.close()
    assert "newer than this hil supports" in run_bad(capsys, ["history", "--db", str(newer)])
    assert "no such file" in run_bad(capsys, ["history", "--config", str(tmp_path / "none.toml")])


def test_real_process_has_no_traceback(tmp_path):
    missing = tmp_path / "x.db"
    proc = subprocess.run([sys.executable, "-m", "hil", "show", "last", "--db", str(missing)],
                          cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr == f"hil: error: --db: {missing}: no such database\n"
