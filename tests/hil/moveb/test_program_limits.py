"""MOVEB programs with absurd values are refused naming the file and line (issue 19: a coordinate of
4e12 mm ran the planner out of memory and exited 70)."""

from __future__ import annotations

from pathlib import Path

import pytest

from hil.cli import main
from hil.errors import InputError
from hil.moveb.program import load_program, parse_program

EXAMPLES = Path(__file__).resolve().parents[3] / "hil" / "moveb" / "examples"
GOOD = "MOVEB 400 0 300  0 0 1  1 0 0  0.5 0.2\nMOVEB 400 100 300  0 0 1  1 0 0  0.5 0.2\n"


def test_a_coordinate_of_4e12_is_refused_by_moveb_plan(tmp_path, capsys) -> None:
    prog = tmp_path / "far.moveb"
    prog.write_text(GOOD + "# far away\nMOVEB 4e12 100 300  0 0 1  1 0 0  0.5 0.2\n")
    out = tmp_path / "samples.csv"
    code = main(["moveb", "plan", str(prog), "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert err == f"hil: error: {prog}: line 4: X: must be in [-5000, 5000] mm, got 4e12"
    assert not out.exists()


@pytest.mark.parametrize(("line", "says"), [
    ("MOVEB 400 -6000 300  0 0 1  1 0 0  0.5 0.2", "Y: must be in [-5000, 5000] mm, got -6000"),
    ("MOVEB 400 100 1e300  0 0 1  1 0 0  0.5 0.2", "Z: must be in [-5000, 5000] mm, got 1e300"),
    ("MOVEB 500 100 300  0 0 1  1 0 0  1e300 0.2",
     "D (chord-height error): must be in [0.0001, 100] mm, got 1e300"),
    ("MOVEB 500 100 300  0 0 1  1 0 0  0.5 1e-300",
     "E (point error): must be in [0.0001, 100] mm, got 1e-300"),
    ("MOVEB 500 100 300  0 0 1  1 0 0  0.5 250", "E (point error): must be in [0.0001, 100] mm, got 250"),
    ("MOVEB 500 100 300  0 0 1  1 0 0  0.5 1e-320", "E (point error): got 1e-320, a denormal number"),
])
def test_absurd_values_name_the_line(line, says) -> None:
    with pytest.raises(InputError, match=r"^p\.moveb: line 3: ") as info:
        parse_program(GOOD + line + "\n", "p.moveb")
    assert says in str(info.value)


def test_the_limits_admit_a_large_cell_and_the_examples() -> None:
    """A point 5 m out and tolerances from 0.1 µm to 100 mm are still programs."""
    text = ("MOVEB 5000 0 -5000  0 0 1  1 0 0  100 1e-4\n"
            "MOVEB 0 0 0  0 0 1  1 0 0  1e-4 100\n")
    assert len(parse_program(text, "edge.moveb").points) == 2
    for example in sorted(EXAMPLES.glob("*.moveb")):
        assert len(load_program(example).points) >= 2
