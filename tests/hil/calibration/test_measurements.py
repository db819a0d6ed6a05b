import numpy as np
import pytest

from hil.calibration.measurements import read_joints, read_measurements, write_measurements
from hil.errors import InputError

HEADER = "q1,q2,q3,q4,q5,q6,x,y,z"


def write(tmp_path, text, name="m.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_round_trip_and_extra_columns(tmp_path, rng):
    q, p = rng.normal(size=(5, 6)), rng.normal(size=(5, 3))
    path = tmp_path / "m.csv"
    write_measurements(path, q, p)
    meas = read_measurements(path)
    assert np.array_equal(meas.q, q) and np.array_equal(meas.p, p)
    assert meas.lines.tolist() == [2, 3, 4, 5, 6] and len(meas.sha256) == 64
    text = "note,z,y,x,q6,q5,q4,q3,q2,q1\n# a comment\n\nhello,9,8,7,6,5,4,3,2,1\n"
    meas = read_measurements(write(tmp_path, text, "shuffled.csv"))
    assert meas.q.tolist() == [[1, 2, 3, 4, 5, 6]] and meas.p.tolist() == [[7, 8, 9]]
    assert meas.lines.tolist() == [4]


@pytest.mark.parametrize("text,message", [
    ("", r"m.csv: empty file"),
    ("q1,q2,q3,q4,q5,q6,x,y\n1,2,3,4,5,6,7,8\n", r"m.csv: line 1: missing column\(s\) z"),
    (HEADER + "\n", r"m.csv: no data rows"),
    (HEADER + "\n1,2,3,4,5,6,7,8,9\n1,2,3,4,5,6,7,8\n", r"m.csv: line 3: expected 9 fields, got 8"),
    (HEADER + "\n1,2,abc,4,5,6,7,8,9\n", r"m.csv: line 2, column q3: 'abc' is not a number"),
    (HEADER + "\n1,2,3,4,5,6,nan,8,9\n", r"m.csv: line 2, column x: expected a finite number, got nan"),
    (HEADER + "\n1,2,3,4,5,6,7,inf,9\n", r"m.csv: line 2, column y: expected a finite number, got inf"),
    ("q1,q1,q2,q3,q4,q5,q6,x,y,z\n", r"column\(s\) q1 appear twice"),
])
def test_malformed_files_name_the_line_and_column(tmp_path, text, message):
    with pytest.raises(InputError, match=message):
        read_measurements(write(tmp_path, text))


def test_missing_file_and_binary(tmp_path):
    with pytest.raises(InputError, match="nope.csv: no such file"):
        read_measurements(tmp_path / "nope.csv")
    path = tmp_path / "bin.csv"
    path.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(InputError, match="bin.csv: not a UTF-8 text file"):
        read_measurements(path)


def test_joint_files_need_only_joints(tmp_path):
    q, lines = read_joints(write(tmp_path, "q1,q2,q3,q4,q5,q6\n0,0,0,0,0,0\n"))
    assert q.shape == (1, 6) and lines.tolist() == [2]


def test_directions_are_read_when_all_six_columns_are_there(tmp_path):
    q = np.zeros((2, 6)) + 0.1
    p = np.ones((2, 3))
    d = np.array([[1, -1, 0, 1, 1, -1], [-1, 1, 1, 0, -1, 1]], dtype=float)
    write_measurements(tmp_path / "d.csv", q, p, d)
    meas = read_measurements(tmp_path / "d.csv")
    assert np.array_equal(meas.directions, d)
    assert np.array_equal(meas.subset(np.array([False, True])).directions, d[1:])
    write_measurements(tmp_path / "plain.csv", q, p)
    assert read_measurements(tmp_path / "plain.csv").directions is None


def test_a_bad_direction_names_line_and_column(tmp_path):
    header = "q1,q2,q3,q4,q5,q6,x,y,z,d1,d2,d3,d4,d5,d6\n"
    (tmp_path / "bad.csv").write_text(header + "0,0,0,0,0,0,1,1,1,1,1,0.5,1,1,1\n")
    with pytest.raises(InputError, match=r"bad.csv: line 2, column d3: '0.5' is not a direction"):
        read_measurements(tmp_path / "bad.csv")
    (tmp_path / "some.csv").write_text("q1,q2,q3,q4,q5,q6,x,y,z,d1,d2\n0,0,0,0,0,0,1,1,1,1,1\n")
    with pytest.raises(InputError,
                       match=r"some.csv: line 1: missing column\(s\) d3, d4, d5, d6 \(the directions form"):
        read_measurements(tmp_path / "some.csv")
