from __future__ import annotations

import re

import numpy as np
import pytest

from hil.errors import InputError
from hil.moveb.program import load_program, parse_program

GOOD = "MOVEB 0 0 0  0 0 1  1 0 0  0.5 0.2\nMOVEB 10 0 0  0 0 1  1 0 0  0.5 0.2\n"


def test_parses_comments_blank_lines_and_groups() -> None:
    text = ("# header\n\nmoveb 0 0 0 0 0 1 1 0 0 0.5 0.2  # inline\n"
            "MOVEB 10 0 0 0 0 1 1 0 0 0.5 0.2\nMOVEB 10 10 0 0 0 1 1 0 0 1 0.1\n"
            "MOVEB 20 10 0 0 0 1 1 0 0 1 0.1\n")
    prog = parse_program(text, "p.moveb")
    assert [p.line for p in prog.points] == [3, 4, 5, 6]
    assert [(g.start, g.stop) for g in prog.groups()] == [(0, 2), (2, 4)]
    assert np.allclose(prog.positions[1], [10, 0, 0])


@pytest.mark.parametrize(("text", "needle"), [
    (GOOD + "MOVE 1 2 3 0 0 1 1 0 0 1 1\n", "line 3: expected MOVEB"),
    (GOOD + "MOVEB 1 2 3 0 0 1 1 0 0 1\n", "line 3: MOVEB needs 11 numbers"),
    (GOOD + "MOVEB 1 2 x 0 0 1 1 0 0 1 1\n", "line 3: Z: 'x' is not a number"),
    (GOOD + "MOVEB 1 2 3 0 0 2 1 0 0 1 1\n", "line 3: the tool axis I J K must have unit length"),
    (GOOD + "MOVEB 1 2 3 0 0 1 0 0 1 1 1\n", "line 3: the tool axes I J K and U V W must be orthogonal"),
    (GOOD + "MOVEB 1 2 3 0 0 1 1 0 0 0 1\n",
     "line 3: D (chord-height error): must be in [0.0001, 100] mm, got 0"),
    (GOOD + "MOVEB 1 2 3 0 0 1 1 0 0 1 -1\n", "line 3: E (point error): must be in [0.0001, 100] mm, got -1"),
    (GOOD + "MOVEB 10 0 0 0 0 1 1 0 0 0.5 0.2\n", "line 3: the point repeats"),
    (GOOD + "MOVEB 0 0 0 0 0 1 1 0 0 0.5 0.2\n", "line 2: the path reverses"),
    (GOOD + "MOVEB 1 2 nan 0 0 1 1 0 0 1 1\n", "line 3: Z: expected a finite number"),
    ("# only one\nMOVEB 0 0 0 0 0 1 1 0 0 1 1\n", "at least two points"),
])
def test_bad_programs_name_the_line(text: str, needle: str) -> None:
    with pytest.raises(InputError, match=re.escape(needle)) as info:
        parse_program(text, "bad.moveb")
    assert str(info.value).startswith("bad.moveb")
    assert "\n" not in str(info.value)


def test_missing_file(tmp_path) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(InputError, match="no such file"):
        load_program(tmp_path / "nope.moveb")
