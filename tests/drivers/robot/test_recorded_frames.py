"""The sweep's joint stream from two records: ur_rtde's file recording and the servo loop's own reads."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drivers.robot.ur import read_frames, union_of_frames


def test_the_recording_is_read_within_the_loops_first_and_last_frame(tmp_path: Path) -> None:
    path = tmp_path / "frames.csv"
    rows = ["timestamp," + ",".join(f"actual_q_{i}" for i in range(6))]
    stamps = (0.99, 1.0, 1.008, 1.008, 1.016, 1.03)
    rows += [f"{t:.6f}," + ",".join(f"{t + i:.6f}" for i in range(6)) for t in stamps]
    path.write_text("\n".join(rows) + "\n")
    t, q = read_frames(str(path), 1.0000003, 1.016)  # the loop's stamps are exact, the file's rounded
    assert t.tolist() == [1.0, 1.008, 1.016]  # a repeated stamp once, nothing outside the loop's span
    assert np.allclose(q[:, 2], t + 2)
    assert read_frames(str(tmp_path / "missing.csv"), 0.0, 1.0) is None
    (tmp_path / "bad.csv").write_text("timestamp,x\n1,2\n")
    assert read_frames(str(tmp_path / "bad.csv"), 0.0, 2.0) is None


def test_every_frame_of_either_record_once_the_loops_values_where_both_have_it() -> None:
    read_t, read_q = np.array([1.0, 1.016]), np.full((2, 6), 7.0)
    rec_t, rec_q = np.array([1.0000004, 1.008, 1.024]), np.zeros((3, 6))
    t, q = union_of_frames(read_t, read_q, rec_t, rec_q)
    assert t.tolist() == [1.0, 1.008, 1.016, 1.024]
    assert q[:, 0].tolist() == [7.0, 0.0, 7.0, 0.0]
