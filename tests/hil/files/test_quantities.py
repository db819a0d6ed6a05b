"""The table of physical quantities (`hil.files.quantities`): one check for files and options alike."""

from __future__ import annotations

import argparse
import math
import sys

import pytest

from hil.errors import InputError
from hil.files.quantities import QUANTITIES, Quantity, check_vector, quantity, real

DENORMAL = 1e-320


def test_every_row_has_a_unit_or_is_dimensionless_a_range_and_a_source() -> None:
    for name, row in QUANTITIES.items():
        assert row.name == name
        assert row.low < row.high, name
        assert math.isfinite(row.low) and math.isfinite(row.high), name
        assert len(row.source) > 20, f"{name}: say where the range comes from (or why it is assumed)"
        if row.integer:
            assert float(row.low).is_integer() and float(row.high).is_integer(), name
        for words, factor in row.confused:
            assert words and factor > 0, name


@pytest.mark.parametrize("name", sorted(QUANTITIES))
def test_no_row_takes_nan_infinities_or_a_denormal(name: str) -> None:
    row = QUANTITIES[name]
    for bad in (math.nan, math.inf, -math.inf):
        assert "finite" in (row.problem(bad) or ""), (name, bad)
    assert "denormal" in (row.problem(DENORMAL) or ""), name
    assert "denormal" in (row.problem(-DENORMAL) or ""), name


@pytest.mark.parametrize("name", sorted(QUANTITIES))
def test_each_row_takes_its_own_ends_unless_open_and_refuses_beyond(name: str) -> None:
    row = QUANTITIES[name]
    assert (row.problem(row.low) is None) == (not row.low_open), name
    assert (row.problem(row.high) is None) == (not row.high_open), name
    step = 1 if row.integer else max(abs(row.high - row.low) * 1e-6, sys.float_info.min * 1e10)
    assert row.problem(row.high + step) is not None, name
    assert row.problem(row.low - step) is not None, name


def test_the_smallest_normal_number_is_still_a_number() -> None:
    row = Quantity("t", "m", 0.0, 1.0, "a test row of at least twenty characters")
    assert row.problem(sys.float_info.min) is None
    assert row.problem(0.0) is None
    assert "denormal" in (row.problem(sys.float_info.min / 2) or "")


@pytest.mark.parametrize(("name", "value", "unit"), [
    ("mounting angle", 90.0, "degrees"),
    ("rotation vector angle", 180.0, "degrees"),
    ("link angle", -90.0, "degrees"),
    ("link offset", 425.0, "millimetres"),
    ("rms threshold", 0.1, "millimetres"),
    ("point spread", 50.0, "micrometres"),
    ("settle time", 300.0, "milliseconds"),
])
def test_a_value_in_a_unit_people_confuse_is_named_with_it(name: str, value: float, unit: str) -> None:
    message = QUANTITIES[name].problem(value) or ""
    assert message.startswith(f"must be in {QUANTITIES[name].span()}"), message
    assert f"looks like {unit}" in message, message


def test_a_value_out_of_range_in_any_unit_says_the_unit_without_guessing_another() -> None:
    message = quantity("mounting angle").problem(1e6) or ""
    assert message == "must be in [-6.28319, 6.28319] rad, got 1000000; the value is in radians"


def test_check_names_where_and_the_range() -> None:
    says = r"^station\.toml: robot\.speed: must be in \(0, 3\.14\] rad/s, got 9$"
    with pytest.raises(InputError, match=says):
        quantity("joint speed").check(9.0, "station.toml: robot.speed")
    assert quantity("joint speed").check(1.0, "x") == 1.0


def test_parse_keeps_the_text_as_written() -> None:
    with pytest.raises(InputError, match=r"^p\.moveb: line 3: D: must be in \[0\.0001, 100\] mm, got 1e300$"):
        quantity("path tolerance").parse("1e300", "p.moveb: line 3: D")
    with pytest.raises(InputError, match=r"'abc' is not a number"):
        quantity("path tolerance").parse("abc", "p.moveb: line 3: D")


def test_json_refuses_what_only_python_calls_a_number() -> None:
    row = quantity("link offset")
    for value, says in ((True, "expected a number, got true"), ("1", 'expected a number, got "1"'),
                        (None, "expected a number, got null"), (10**400, "an integer of 401 digits")):
        with pytest.raises(InputError, match="^m.json: joints\\[0\\].xyz\\[0\\]: ") as info:
            row.json(value, "m.json: joints[0].xyz[0]")
        assert says in str(info.value)
    assert row.json(1, "m.json") == 1.0


def test_an_option_is_a_usage_error_argparse_reports_with_the_option() -> None:
    parser = argparse.ArgumentParser(prog="hil", exit_on_error=False)
    parser.add_argument("--time-limit", type=quantity("search time").option())
    parser.add_argument("--count", type=quantity("pose count").option())
    assert parser.parse_args(["--time-limit", "2.5", "--count", "12"]).count == 12
    for argv, says in ((["--time-limit", "1e-320"], "denormal"), (["--time-limit", "nan"], "finite"),
                       (["--count", "1001"], "must be in [1, 1000]"), (["--count", "1.5"], "invalid int")):
        with pytest.raises(argparse.ArgumentError) as info:
            parser.parse_args(argv)
        assert says in str(info.value) and argv[0] in str(info.value)


def test_a_vector_is_checked_by_component_or_by_length() -> None:
    assert check_vector([0.0, 3.0, 0.0], "rotation vector angle", "t.csv: line 2", norm=True) == (0, 3, 0)
    with pytest.raises(InputError, match=r"^t\.csv: line 2: its length \(rotation vector angle\) must be in "
                                         r"\[0, 6\.28319\] rad, got 180; 180 looks like degrees"):
        check_vector([0.0, 180.0, 0.0], "rotation vector angle", "t.csv: line 2", norm=True)
    with pytest.raises(InputError, match=r"^--mounting\[0\]: must be in .*looks like degrees"):
        check_vector([90.0, 0.0, 0.0], "mounting angle", "--mounting")
    with pytest.raises(InputError, match=r"^--smr\[1\]: .*denormal"):
        check_vector([0.0, DENORMAL, 0.05], "smr offset", "--smr", norm=True)


def test_real_refuses_only_what_no_quantity_takes() -> None:
    assert real(-1e300, "x") == -1e300 and real(0.0, "x") == 0.0
    for bad in (math.nan, math.inf, DENORMAL):
        with pytest.raises(InputError, match="^x: "):
            real(bad, "x")
