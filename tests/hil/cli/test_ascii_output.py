"""Odd environments (issue 31, class 6): an ASCII stdout/stderr gets ASCII spellings, not exit 70; an
input whose kind is ambiguous is refused with what was expected."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

import pytest

from hil.cli.compensate import _is_program
from hil.cli.support.output import degrade_to_ascii
from hil.errors import InputError

ROOT = Path(__file__).resolve().parents[3]


def test_an_ascii_stream_spells_what_it_cannot_encode() -> None:
    raw = io.BytesIO()
    stream = io.TextIOWrapper(raw, encoding="ascii")
    degrade_to_ascii(stream)
    stream.write("RMS 0.05 mm \u2014 \u03c1 = -0.98, 20 \u00b0C, \u00b1 3 \u00b5m, caf\u00e9 \u2603\n")
    stream.flush()
    assert raw.getvalue().decode("ascii") == "RMS 0.05 mm -- rho = -0.98, 20  degC, +/- 3 um, cafe ?\n"


def test_a_utf8_stream_is_left_as_it_is() -> None:
    stream = io.TextIOWrapper(io.BytesIO(), encoding="utf-8")
    degrade_to_ascii(stream)
    assert stream.errors == "strict"


@pytest.mark.timeout(120)
def test_an_error_with_a_unit_under_pythonioencoding_ascii_is_one_ascii_line(tmp_path) -> None:
    """The interpreter's own streams (set up from the environment at start: a subprocess is the test).
    The error names a range in degrees Celsius, which an ASCII stderr could not encode (exit 70)."""
    config = tmp_path / "station.toml"
    config.write_text('[tracker]\nurl = "/dev/ttyUSB0"\ntemperature = -300.0\n')
    env = {**os.environ, "PYTHONIOENCODING": "ascii", "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-m", "hil", "calibrate", "--config", str(config), "--db",
                           str(tmp_path / "c.db")], env=env, capture_output=True, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    line = done.stderr.decode("ascii").strip()
    assert line.endswith("tracker.temperature: must be in [-20, 50]  degC, got -300"), line
    assert not (tmp_path / "c.db").exists()


@pytest.mark.parametrize("name", ["poses.txt", "poses.dat", "poses"])
def test_a_csv_header_with_a_typo_is_neither_kind(name) -> None:
    with pytest.raises(InputError, match=f"^{name}: line 1 'x,y,zz,rx,ry,rz' is a CSV header without the "
                                         "pose columns x,y,z,rx,ry,rz, and the file is no URScript program"):
        _is_program(name, "x,y,zz,rx,ry,rz\n0.4,0.1,0.3,0,3.1,0\n")


def test_the_kinds_still_tell_themselves_apart() -> None:
    assert _is_program("p.txt", "def prog():\n  movel(p[0.4,0.1,0.3,0,3.1,0])\nend\n")
    assert not _is_program("p.txt", "x,y,z,rx,ry,rz\n0.4,0.1,0.3,0,3.1,0\n")
    assert _is_program("p.script", "x,y,zz\n")  # the suffix says it: the program's parser judges it
    assert not _is_program("p.csv", "movel(p[0,0,0,0,0,0])\n")
