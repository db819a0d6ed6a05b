"""Files read line by line are bounded by their lines and the length of a line, not only their size.

64 MiB of newlines or comments, or one line of millions of fields, fit under `MAX_INPUT_BYTES` yet
kept the CSV, MOVEB and TOML readers busy for minutes (issue 31, second pass); `check_text_lines`
refuses them by counting in C, and the station TOML and JSON documents have byte limits of their own.
"""

from __future__ import annotations

import socket
import time

import pytest

from hil.calibration.measurements import read_measurements
from hil.errors import InputError
from hil.files.inputs import (
    MAX_CONFIG_BYTES,
    MAX_JSON_BYTES,
    MAX_LINE_CHARS,
    MAX_TEXT_LINES,
    check_input_file,
    check_text_lines,
    read_input_text,
)
from hil.moveb.program import load_program
from hil.station.config import load_config

HEADER = "q1,q2,q3,q4,q5,q6,x,y,z\n"


def test_a_file_of_more_lines_than_the_bound_is_refused_naming_the_count() -> None:
    with pytest.raises(InputError, match=rf"^m.csv: {MAX_TEXT_LINES + 1} lines; hil reads at most "):
        check_text_lines("\n" * (MAX_TEXT_LINES + 1), "m.csv", "a CSV file")
    check_text_lines("\n" * (MAX_TEXT_LINES - 1), "m.csv", "a CSV file")  # at the bound: read


def test_a_line_longer_than_the_bound_is_refused_naming_its_number() -> None:
    text = "a\nb\n" + "x" * (MAX_LINE_CHARS + 1) + "\nc\n"
    with pytest.raises(InputError, match=rf"^p.moveb: line 3: {MAX_LINE_CHARS + 1} characters long"):
        check_text_lines(text, "p.moveb", "a MOVEB program")
    check_text_lines("x" * MAX_LINE_CHARS + "\n", "p.moveb")  # at the bound: read


@pytest.mark.timeout(60)
@pytest.mark.parametrize("content", ["\n" * (40 << 20), "#\n" * (20 << 20), "q1," * (10 << 20)],
                         ids=["newlines", "comments", "one-line"])
def test_the_measurements_reader_refuses_40_mb_of_lines_at_once(tmp_path, content) -> None:
    """Before the bound each of these took the reader over a minute (killed); now the count is done
    in C: a second even on a loaded machine (the bound the test allows is ten times that)."""
    path = tmp_path / "m.csv"
    path.write_text(HEADER + content)
    start = time.process_time()
    with pytest.raises(InputError, match="m.csv: (line 2: .* characters long|.* lines; hil reads at most)"):
        read_measurements(path)
    assert time.process_time() - start < 10


@pytest.mark.parametrize("reader", [load_program, load_config], ids=["moveb", "toml"])
def test_line_based_readers_share_the_bound(tmp_path, reader) -> None:
    path = tmp_path / "f.txt"
    path.write_text("\n" * (MAX_TEXT_LINES + 1))
    with pytest.raises(InputError, match="f.txt: .* lines; hil reads at most"):
        reader(path)


def test_a_station_config_over_its_byte_limit_is_refused_before_tomllib(tmp_path) -> None:
    path = tmp_path / "s.toml"
    path.write_text("# " + "x" * MAX_CONFIG_BYTES + "\n")
    with pytest.raises(InputError, match=r"s.toml: 1 MiB is larger than hil reads \(1 MiB\); expected"):
        load_config(path)


def test_json_is_not_held_to_the_line_bound_but_to_its_byte_limit(tmp_path) -> None:
    """A result written on one line is JSON as good as an indented one; 16 MiB bounds the parse."""
    one_line = tmp_path / "r.json"
    one_line.write_text('{"x": "' + "y" * (MAX_LINE_CHARS + 10) + '"}')
    assert read_input_text(one_line, "a JSON file", line_based=False).startswith('{"x"')
    big = tmp_path / "big.json"
    big.write_text("[" + "1," * (MAX_JSON_BYTES // 2) + "1]")
    with pytest.raises(InputError, match=r"big.json: 16 MiB is larger than hil reads \(16 MiB\)"):
        read_input_text(big, "a JSON file", line_based=False, limit=MAX_JSON_BYTES)


def test_a_socket_is_named_as_one(tmp_path) -> None:
    """open() of a Unix socket fails with ENXIO ("No such device or address"): the error says what
    the file is instead."""
    path = tmp_path / "s.sock"
    with socket.socket(socket.AF_UNIX) as s:
        s.bind(str(path))
        with pytest.raises(InputError, match=r"s.sock: is a socket, not a regular file; expected a CSV file"):
            check_input_file(path, "a CSV file")
