"""File contents that used to escape the error contract (issue 19): exit 2 and one line naming the file
and line, never exit 70, never a value accepted that no instrument or arm could have produced."""

from __future__ import annotations

from pathlib import Path

import pytest

from hil.calibration.measurements import read_measurements
from hil.cli import main
from hil.errors import InputError


@pytest.fixture(scope="module")
def station(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("station")
    assert main(["synth", "--ideal", "--robot", "ur5e", "--poses", "30", "--validation", "10", "--seed", "5",
                 "--out-dir", str(out)]) == 0
    return out


def run_bad(capsys, argv: list[str], out: Path | None = None) -> str:
    """Run the CLI expecting exit 2 with one line on stderr and nothing written to `out`."""
    code = main(argv)
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    if out is not None:
        assert not out.exists()
    return err


def with_cell(station: Path, tmp_path: Path, column: str, text: str, row: int = 2,
              name: str = "bad.csv") -> Path:
    """A copy of the measurements with the cell `column` of data row `row` (1-based) set to `text`."""
    lines = (station / "measurements.csv").read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[row].split(",")
    cells[header.index(column)] = text
    lines[row] = ",".join(cells)
    bad = tmp_path / name
    bad.write_text("\n".join(lines) + "\n")
    return bad


# --- CSV ---------------------------------------------------------------------------------------------

def test_a_field_over_the_csv_limit_names_the_file_and_line(station, tmp_path, capsys) -> None:
    bad = with_cell(station, tmp_path, "x", '"' + "1" * (128 * 1024 + 10) + '"', row=3)
    out = tmp_path / "model.json"
    err = run_bad(capsys, ["identify", "--robot", "ur5e", "--measurements", str(bad), "--out", str(out)],
                  out)
    assert "bad.csv: line 4:" in err and "field larger than field limit" in err
    err = run_bad(capsys, ["fk", "--model", str(station / "truth.json"), "--joints", str(bad),
                           "--out", str(tmp_path / "p.csv")], tmp_path / "p.csv")
    assert "bad.csv: line 4:" in err


def test_the_oversized_field_is_named_by_its_physical_line() -> None:
    """A quoted field may span lines; the error names the line the reader stopped on, not the row."""
    from hil.files.inputs import csv_rows

    text = 'x\n"1\n2"\n"' + "9" * 200_000 + '"\n'
    with pytest.raises(InputError, match=r"^t\.csv: line 4: not a usable CSV row \(field larger"):
        csv_rows(text, "t.csv")


def test_csv_rows_keep_their_line_numbers() -> None:
    from hil.files.inputs import csv_rows

    assert csv_rows("a,b\n\n1,2\n", "t.csv") == [(1, ["a", "b"]), (2, []), (3, ["1", "2"])]


@pytest.mark.parametrize(("column", "text", "says"), [
    ("y", "1e308", "1e+308 m is beyond a laser tracker's range"),
    ("z", "-80.5", "-80.5 m is beyond a laser tracker's range"),
    ("q3", "20", "20 rad is beyond the joint limits of every UR arm"),
    ("q1", "-6.5", "-6.5 rad is beyond the joint limits of every UR arm"),
])
def test_a_measurement_out_of_physical_range_names_line_and_column(station, tmp_path, capsys, column,
                                                                   text, says) -> None:
    bad = with_cell(station, tmp_path, column, text, row=5)
    out = tmp_path / "model.json"
    err = run_bad(capsys, ["identify", "--robot", "ur5e", "--measurements", str(bad), "--out", str(out)],
                  out)
    assert f"bad.csv: line 6, column {column}: {says}" in err
    err = run_bad(capsys, ["validate", "--model", str(station / "truth.json"), "--measurements",
                           str(bad)])
    assert f"bad.csv: line 6, column {column}:" in err


def test_values_inside_the_ranges_still_read(station, tmp_path) -> None:
    """The limits sit outside what an arm and a tracker produce: extremes just inside them pass."""
    elbow = with_cell(station, tmp_path, "q3", "3.2", name="elbow.csv")  # just past π, in the margin
    far = with_cell(station, tmp_path, "x", "79.9", name="far.csv")
    assert read_measurements(elbow).q[1, 2] == 3.2
    assert read_measurements(far).p[1, 0] == 79.9


# --- JSON --------------------------------------------------------------------------------------------

@pytest.fixture
def deep_json(tmp_path) -> Path:
    f = tmp_path / "deep.json"
    f.write_text("[" * 100_000 + "]" * 100_000)
    return f


def test_json_nested_100000_deep_is_refused_for_every_json_input(station, tmp_path, capsys,
                                                                 deep_json) -> None:
    commands = [
        ["fk", "--model", str(deep_json), "--joints", str(station / "measurements.csv"),
         "--out", str(tmp_path / "p.csv")],
        ["validate", "--model", str(deep_json), "--measurements", str(station / "validation.csv")],
        ["export", "--model", str(deep_json), "--format", "urdf", "--out", str(tmp_path / "a.urdf")],
        ["synth", "--truth", str(deep_json), "--out-dir", str(tmp_path / "synth")],
        ["report", "--result", str(deep_json), "--out", str(tmp_path / "r.html")],
    ]
    for argv in commands:
        err = run_bad(capsys, argv)
        assert err.endswith("deep.json: not a usable JSON file (nested too deeply)"), (argv, err)
    assert not any((tmp_path / n).exists() for n in ("p.csv", "a.urdf", "synth", "r.html"))


def test_an_integer_beyond_python_s_digit_limit_is_named(tmp_path) -> None:
    from hil.files.inputs import parse_json

    with pytest.raises(InputError, match=r"^m\.json: not a usable JSON file \(.*digits"):
        parse_json('{"smr": [' + "9" * 5000 + "]}", "m.json")


def test_parse_json_keeps_the_line_of_a_syntax_error() -> None:
    from hil.files.inputs import parse_json

    with pytest.raises(InputError, match=r"^m\.json: line 2: not valid JSON"):
        parse_json('{"a": 1,\n}', "m.json")


@pytest.mark.parametrize(("value", "says"), [
    (True, "expected a number, got true"),
    ("1", 'expected a number, got "1"'),
    (None, "expected a number, got null"),
    ([1.0], "expected a number, got list"),
    (float("nan"), "expected a finite number in [-5, 5] m, got nan; the value is in metres"),
    (10**400, "expected a finite number, got an integer of 401 digits"),
    (6e6, "must be in [-5, 5] m, got 6000000; the value is in metres"),
    (6.0, "must be in [-5, 5] m, got 6; 6 looks like millimetres: the value is in metres"),
    (1e-320, "a denormal number (non-zero, below 2.23e-308), not a physical value; expected a value in "
             "[-5, 5] m; the value is in metres"),
])
def test_json_number_refuses_what_is_not_a_plausible_number(value, says) -> None:
    from hil.files.inputs import json_number

    with pytest.raises(InputError, match=r"^f\.json: a\.b\[0\]: ") as info:
        json_number(value, "f.json: a.b[0]", "keep-in corner")
    assert str(info.value).endswith(says)
    assert json_number(-5, "f.json: a", "keep-in corner") == -5.0


# --- TOML --------------------------------------------------------------------------------------------

def test_a_config_nested_100000_deep_is_refused_before_the_store_is_made(tmp_path, capsys) -> None:
    cfg = tmp_path / "deep.toml"
    cfg.write_text("a = " + "[" * 100_000 + "]" * 100_000 + "\n")
    db = tmp_path / "x.db"
    err = run_bad(capsys, ["calibrate", "--config", str(cfg), "--db", str(db)], db)
    assert err.endswith("deep.toml: not a usable TOML file (nested too deeply)")
