"""`hil robots` and `hil robot SERIAL`: the fleet table, one robot's history, marking a calibration bad
or good again, exporting the current model, and bad input (exit 2, one line, nothing written)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from sqlalchemy import func, select

from hil.cli import main
from hil.store import Store
from hil.store import tables as tb
from hil.store.fleet import current_model
from tests.hil.fleet_data import (
    HIT_PARAMETER,
    HIT_ROBOT,
    REJECTING,
    ROBOTS,
    STATIONS,
    STEADY,
    Fleet,
    fingerprint,
)


def run(capsys, argv: list[str]) -> tuple[str, str]:
    code = main(argv)
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return captured.out, captured.err


def run_bad(capsys, argv: list[str]) -> str:
    code = main(argv)
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert code == 2, (code, err)
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert captured.out == ""
    return err


def marks_in(db: Path) -> int:
    with Store.open(db, readonly=True) as store, store.reading() as conn:
        return conn.execute(select(func.count()).select_from(tb.marks)).scalar_one()


def day(campaign: str) -> str:
    """The local date a campaign was created, as its id says it (YYYYMMDD-...)."""
    return f"{campaign[:4]}-{campaign[4:6]}-{campaign[6:8]}"


def sha(location: Path | str) -> str:
    return fingerprint(location)


def shown(db: str) -> str:
    """How the ``database:`` line names a store: the absolute file, or the URL as given."""
    return db if "://" in db else str(Path(db).resolve())


# --- hil robots -----------------------------------------------------------------------------------------
def test_robots_lists_the_fleet(fleet_store_location, built_fleet: Fleet, capsys):
    db = str(fleet_store_location)
    out, err = run(capsys, ["robots", "--db", db])
    assert err.strip() == f"database: {shown(db)}"
    lines = out.splitlines()
    assert lines[0].split() == ["ROBOT", "TYPE", "LAST", "CALIB", "RESULT", "VAL", "mm", "AGE", "STATION",
                                "CURRENT"]
    rows = {line.split()[0]: line for line in lines[1:4]}
    assert sorted(rows) == sorted(ROBOTS)
    assert "accepted" in rows[STEADY] and rows[STEADY].endswith("= last")
    current = built_fleet.campaigns[REJECTING][1]
    assert "rejected" in rows[REJECTING] and rows[REJECTING].endswith(day(current))
    assert lines[4].startswith("3 robots")
    assert all(len(line) < 80 for line in lines)  # the 80x24 terminal


def _one_robot_store(tmp_path: Path, serial: str, station: str) -> str:
    db = tmp_path / "one.db"
    with Store.open(db) as store:
        cid = store.create_campaign({"station": {"name": station}, "robot": {"type": "ur5e"}},
                                    {"type": "ur5e", "serial": serial})
        store.set_status(cid, "accepted")
    return str(db)


def test_one_robot_is_one_robot(tmp_path, capsys):
    out, _ = run(capsys, ["robots", "--db", _one_robot_store(tmp_path, "20235500101", "eol-cell-1")])
    assert out.splitlines()[-1].startswith("1 robot, ")  # not "1 robots"


def test_a_pipe_gets_every_cell_whole_and_a_narrow_terminal_a_clipped_table(tmp_path, capsys, monkeypatch):
    serial, station = "UR-LINE4-20235500101-B", "end-of-line cell north 7"
    db = _one_robot_store(tmp_path, serial, station)
    out, _ = run(capsys, ["robots", "--db", db])  # captured: not a terminal
    row = out.splitlines()[1]
    assert row.split()[0] == serial and station in row and "…" not in out
    # on an 80-column terminal the text columns are cut to fit, an ellipsis marking the cut
    monkeypatch.setattr("sys.stdout.isatty", lambda: True, raising=False)
    monkeypatch.setattr("shutil.get_terminal_size", lambda *a, **k: __import__("os").terminal_size((80, 24)))
    out, _ = run(capsys, ["robots", "--db", db])
    assert all(len(line) < 80 for line in out.splitlines())
    assert serial[:11] + "…" in out and station[:10] + "…" in out
    # a terminal wide enough shows it whole
    monkeypatch.setattr("shutil.get_terminal_size", lambda *a, **k: __import__("os").terminal_size((200, 24)))
    out, _ = run(capsys, ["robots", "--db", db])
    assert serial in out and station in out and "…" not in out


def test_an_interrupted_calibration_is_shown_in_progress_not_as_the_last(fleet_store_location,
                                                                          built_fleet: Fleet, capsys):
    db = str(fleet_store_location)
    with Store.open(db) as store:
        cid = store.create_campaign({"station": {"name": STATIONS[0]}, "robot": {"type": "ur5e"}},
                                    {"type": "ur5e", "serial": STEADY})
        store.set_status(cid, "interrupted")
    out, _ = run(capsys, ["robots", "--db", db])
    lines = out.splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith(STEADY))
    assert "accepted" in lines[at] and lines[at].endswith("= last")  # its last finished calibration
    assert lines[at + 1].strip().startswith(f"in progress: {cid} interrupted (resumable)")
    assert "interrupted" not in "".join(lines[:at + 1])
    assert lines[-1].startswith("3 robots, 1 with a calibration in progress;")
    doc = json.loads(run(capsys, ["robots", "--db", db, "--json"])[0])
    steady = next(r for r in doc["robots"] if r["serial"] == STEADY)
    assert steady["last"] == built_fleet.campaigns[STEADY][-1] and steady["in_progress"] == cid


def test_robots_json_and_station(fleet_store_location, built_fleet: Fleet, capsys):
    db = str(fleet_store_location)
    out, err = run(capsys, ["robots", "--db", db, "--json"])
    doc = json.loads(out)
    assert err == "" and doc["database"] == db
    by = {r["serial"]: r for r in doc["robots"]}
    assert sorted(by) == sorted(ROBOTS)
    assert by[REJECTING]["current"] == built_fleet.campaigns[REJECTING][1]
    assert by[STEADY]["last"] == by[STEADY]["current"] == built_fleet.campaigns[STEADY][-1]
    out, _ = run(capsys, ["robots", "--db", db, "--json", "--station", STATIONS[1]])
    assert {r["station"] for r in json.loads(out)["robots"]} == {STATIONS[1]}
    err = run_bad(capsys, ["robots", "--db", db, "--station", "cell-9"])
    assert "--station: no station named 'cell-9'" in err


def test_robots_on_a_store_without_robots(tmp_path, capsys):
    db = tmp_path / "empty.db"
    Store.open(db).close()
    out, _ = run(capsys, ["robots", "--db", str(db)])
    assert out.strip() == f"no robots in {db}"


# --- hil robot SERIAL -----------------------------------------------------------------------------------
def test_robot_shows_its_history_and_the_geometry_that_moved(fleet_store_location, built_fleet: Fleet,
                                                           capsys):
    db = str(fleet_store_location)
    ids = built_fleet.campaigns[HIT_ROBOT]
    out, _ = run(capsys, ["robot", HIT_ROBOT, "--db", db])
    lines = out.splitlines()
    assert lines[0] == f"robot {HIT_ROBOT}: ur5e (UR5E, software 5.15.0)"
    assert lines[1].split() == ["first", "seen", f"{day(ids[0])},", "3", "calibrations"]
    assert lines[2] == "  factory calibration  not read"
    station = built_fleet.stations[ids[2]]
    assert lines[3] == f"  current model        campaign {ids[2]} ({day(ids[2])}, {station})"
    table = [line for line in lines if any(cid in line for cid in ids) and "->" not in line][1:]
    assert [next(word for word in line.split() if word in ids) for line in table] == ids
    assert table[2].startswith("*") and not table[0].startswith("*")
    at = lines.index(f"  {ids[1]} -> {ids[2]}  MOVED")
    assert lines[at + 1].strip().startswith(f"{HIT_PARAMETER} +0.") and lines[at + 1].endswith("σ)")
    assert f"  {ids[0]} -> {ids[1]}  no change (18 parameters)" in lines
    assert "(moved: |Δ| > 3.5·sqrt(σa² + σb²)):" in out
    assert all(len(line) < 80 for line in lines)
    out, _ = run(capsys, ["robot", HIT_ROBOT, "--db", db, "--json"])
    doc = json.loads(out)
    assert [c["id"] for c in doc["calibrations"]] == ids and doc["current"] == ids[2]
    assert [(m["before"], m["after"]) for m in doc["moved"]] == [(ids[1], ids[2])]
    assert doc["moved"][0]["changes"][0]["name"] == HIT_PARAMETER and doc["robot"]["controller"] is None
    out, _ = run(capsys, ["robot", STEADY, "--db", db])
    assert "MOVED" not in out


def test_the_factory_calibration_is_shown_when_read(fleet_store_location, capsys):
    with Store.open(fleet_store_location) as store:
        store.set_controller(STEADY, {"delta_theta": [1e-4, -2e-4, 0, 0, 0, 0],
                                      "delta_a": [0, 3e-4, 0, 0, 0, 0],
                                      "delta_d": [1e-3, 0, 0, -2e-3, 0, 0], "delta_alpha": [0] * 6})
    out, _ = run(capsys, ["robot", STEADY, "--db", str(fleet_store_location)])
    assert ("  factory calibration  read from the controller, largest deltas:\n"
            "                       θ 0.200 mrad, a 0.300 mm, d 2.000 mm, α 0.000 mrad\n") in out


def test_mark_bad_falls_back_and_mark_good_restores(fleet_store_location, built_fleet: Fleet, capsys):
    db = str(fleet_store_location)
    ids = built_fleet.campaigns[HIT_ROBOT]
    out, err = run(capsys, ["robot", HIT_ROBOT, "--db", db, "--mark-bad", "last", "--reason",
                            "dropped during transport", "--json"])
    assert f"marked campaign {ids[2]} bad: the current model is now campaign {ids[1]}'s" in err
    doc = json.loads(out)
    assert doc["current"] == ids[1] and doc["marked"]["bad"] is True and doc["moved"] == []
    assert doc["calibrations"][2]["mark"]["reason"] == "dropped during transport"
    out, _ = run(capsys, ["robots", "--db", db])
    row = next(line for line in out.splitlines() if line.startswith(HIT_ROBOT))
    assert "marked bad" in row and not row.endswith("= last")
    out, _ = run(capsys, ["robot", HIT_ROBOT, "--db", db])
    assert f"x {ids[2]}" in out and f"* {ids[1]}" in out and "dropped during transport" in out
    _, err = run(capsys, ["robot", HIT_ROBOT, "--db", db, "--mark-good", ids[2][:17], "--reason",
                          "the hit was real; this calibration is right"])
    assert f"now campaign {ids[2]}'s" in err
    with Store.open(db, readonly=True) as store:
        assert current_model(store, HIT_ROBOT)[0] == ids[2]
    assert marks_in(fleet_store_location) == 2


def test_export_writes_the_current_model(fleet_store_location, built_fleet: Fleet, tmp_path, capsys):
    db = str(fleet_store_location)
    out_json, out_urdf = tmp_path / "model.json", tmp_path / "robot.urdf"
    _, err = run(capsys, ["robot", REJECTING, "--db", db, "--export-model", str(out_json)])
    current = built_fleet.campaigns[REJECTING][1]
    assert f"wrote {out_json} (current model: campaign {current})" in err
    with Store.open(db, readonly=True) as store:
        assert json.loads(out_json.read_text()) == current_model(store, REJECTING)[1]
    run(capsys, ["robot", REJECTING, "--db", db, "--export-model", str(out_urdf)])
    assert out_urdf.read_text().lstrip().startswith("<?xml") and "<robot" in out_urdf.read_text()
    run(capsys, ["robot", REJECTING, "--db", db, "--mark-bad", current, "--reason", "wrong SMR nest",
                 "--export-model", str(out_json), "--format", "json"])  # marked first, then exported
    assert json.loads(out_json.read_text())["fit"] is not None
    with Store.open(db, readonly=True) as store:
        assert json.loads(out_json.read_text()) == current_model(store, REJECTING)[1]
        assert current_model(store, REJECTING)[0] == built_fleet.campaigns[REJECTING][0]


# --- bad input: one line, exit 2, nothing written --------------------------------------------------------
def bad_cases(fleet: Fleet) -> list[tuple[list[str], str]]:
    steady, other = fleet.campaigns[STEADY], fleet.campaigns[HIT_ROBOT]
    return [
        (["robot", "999"], "no robot with serial '999'"),
        (["robot", STEADY, "--mark-bad", "nope", "--reason", "r"], "no campaign 'nope'"),
        (["robot", STEADY, "--mark-bad", steady[0], "--reason", "  "], "--mark-bad: needs --reason"),
        (["robot", STEADY, "--mark-good", steady[0]], "--mark-good: needs --reason"),
        (["robot", STEADY, "--reason", "why"], "--reason: only with --mark-bad or --mark-good"),
        (["robot", STEADY, "--mark-bad", other[0], "--reason", "r"],
         f"campaign {other[0]} is not robot {STEADY}'s: it calibrated robot {HIT_ROBOT}"),
        (["robot", STEADY, "--mark-bad", fleet.anonymous, "--reason", "r"],
         "it calibrated a robot whose serial was not read"),
        (["robot", STEADY, "--mark-bad", "2023", "--reason", "r"], "matches several calibrations of robot"),
        (["robot", STEADY, "--mark-bad", steady[0], "--mark-good", steady[1], "--reason", "r"],
         "not allowed with argument"),
        (["robot", STEADY, "--format", "urdf"], "--format: only with --export-model"),
        (["robot", "999", "--mark-bad", "last", "--reason", "r"], "no robot with serial '999'"),
    ]


def test_bad_input_is_one_line_and_writes_nothing(fleet_store_location, built_fleet: Fleet, capsys):
    db = str(fleet_store_location)
    for argv, message in bad_cases(built_fleet):
        err = run_bad(capsys, [*argv, "--db", db])
        assert message in err, (argv, err)
    assert marks_in(fleet_store_location) == 0


def test_bad_stores_and_export_paths(fleet_store_location, tmp_path, capsys):
    db = str(fleet_store_location)
    missing = tmp_path / "missing.db"
    for argv in (["robots"], ["robot", STEADY], ["robot", STEADY, "--mark-bad", "last", "--reason", "r"]):
        assert "missing.db" in run_bad(capsys, [*argv, "--db", str(missing)])
        assert not missing.exists()
    before = sha(fleet_store_location)
    if isinstance(fleet_store_location, Path):  # a file an export could overwrite
        err = run_bad(capsys, ["robot", STEADY, "--db", db, "--export-model", db])
        assert "--export-model" in err and "is the store" in err
    assert "folder" in run_bad(capsys, ["robot", STEADY, "--db", db, "--export-model",
                                        str(tmp_path / "no" / "m.json")])
    assert sha(fleet_store_location) == before
    with Store.open(db) as store:  # no accepted calibration left: no current model to export
        for c in store.campaigns(None):
            if c.serial == STEADY:
                store.set_status(c.id, "rejected")
    err = run_bad(capsys, ["robot", STEADY, "--db", db, "--export-model", str(tmp_path / "m.json")])
    assert f"robot {STEADY}: has no current model" in err and not (tmp_path / "m.json").exists()


@pytest.mark.parametrize("command", ["robots", "robot", "fleet-report"])
def test_db_help_says_it_takes_a_url(command, capsys):
    assert main([command, "--help"]) == 0
    assert "postgresql:// URL" in " ".join(capsys.readouterr().out.split())
