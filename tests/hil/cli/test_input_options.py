"""Options naming an input file are checked for what the file is while the command line is parsed
(`hil.cli.support.options.input_file`): before the command loads its libraries, so ``hil report
--result FIFO`` is refused in a fraction of a second, not after matplotlib (issue 31, second pass)."""

from __future__ import annotations

import argparse
import os

import pytest

from hil.cli import main
from hil.cli.support.options import JSON_FILE, input_file


def test_a_fifo_is_a_usage_error_naming_the_option(tmp_path) -> None:
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    parser = argparse.ArgumentParser(exit_on_error=False)
    parser.add_argument("--model", type=JSON_FILE)
    with pytest.raises(argparse.ArgumentError,
                       match=r"argument --model: .*pipe: is a FIFO \(named pipe\), not a regular file; "
                             r"expected a JSON file"):
        parser.parse_args(["--model", str(fifo)])


def test_a_missing_file_is_left_to_its_reader_and_a_good_one_passes_unchanged(tmp_path) -> None:
    """A missing file is named by the reader (after the other options' values are checked)."""
    check = input_file("a CSV file", limit=10)
    assert check(str(tmp_path / "nothing")) == str(tmp_path / "nothing")
    good = tmp_path / "q.csv"
    good.write_text("q1\n")
    assert check(str(good)) == str(good)
    good.write_text("q1\n" * 10)
    with pytest.raises(argparse.ArgumentTypeError,
                       match=r"q.csv: 30 bytes is larger than hil reads \(10 bytes\)"):
        check(str(good))


def test_report_refuses_a_fifo_before_loading_the_report(tmp_path, capsys, monkeypatch) -> None:
    """The report's libraries (hil.report: matplotlib) are not imported to refuse a FIFO."""
    import sys

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    monkeypatch.delitem(sys.modules, "hil.report", raising=False)
    monkeypatch.setitem(sys.modules, "hil.report", None)  # importing it would raise
    assert main(["report", "--result", str(fifo), "--out", str(tmp_path / "r.html")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--result" in err and "FIFO" in err
    assert not (tmp_path / "r.html").exists()
