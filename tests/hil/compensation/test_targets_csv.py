"""Compensating a CSV of tool poses: the round trip lands on the target, columns pass through, and a
bad table or an unreachable row is named by its line."""

from __future__ import annotations

import csv
import io

import numpy as np
import pinocchio as pin
import pytest

from hil.arm.ik import UnreachableError
from hil.compensation.poses import CANONICAL_NEAR, to_se3, to_vector
from hil.compensation.targets_csv import compensate_csv, looks_like_csv
from hil.errors import InputError
from tests.hil.compensation.world import assert_lands, assert_same_pose, make_world


def _rows(text: str) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(text)))


@pytest.mark.parametrize(("seed", "cancelling"), [(1, False), (2, False), (3, True)])
@pytest.mark.parametrize("with_q", [True, False])
def test_round_trip_lands_on_every_target(seed: int, cancelling: bool, with_q: bool) -> None:
    world = make_world(seed, cancelling)
    tcp = to_se3([0.01, -0.02, 0.12, 0.0, 0.1, 0.0])
    comp = world.compensator(tcp)
    Q = world.configurations(25) if with_q else np.asarray(CANONICAL_NEAR) + np.cumsum(
        world.rng.uniform(-0.03, 0.03, (25, 6)), axis=0)  # a path: each row near the previous one
    targets = [comp.accurate_pose(q) for q in Q]
    header = "label,x,y,z,rx,ry,rz" + (",q1,q2,q3,q4,q5,q6" if with_q else "")
    lines = [header]
    for i, (q, T) in enumerate(zip(Q, targets, strict=True)):
        seed_q = q + world.rng.uniform(-0.05, 0.05, 6)
        lines.append(",".join([f"p{i}", *(repr(float(v)) for v in to_vector(T))]
                              + ([repr(float(v)) for v in seed_q] if with_q else [])))
    out, summary = compensate_csv("\n".join(lines) + "\n", "t.csv", comp, CANONICAL_NEAR)
    rows = _rows(out)
    assert [r["label"] for r in rows] == [f"p{i}" for i in range(25)]
    assert list(rows[0]) == header.split(",")
    for q, T, row in zip(Q, targets, rows, strict=True):
        command = to_se3([float(row[c]) for c in ("x", "y", "z", "rx", "ry", "rz")])
        assert_lands(comp, command, q, T)
    assert len(summary.moved) == 25
    doc = summary.as_dict()
    assert 0.1 < doc["shift_mm"]["mean"] <= doc["shift_mm"]["max"] < 50  # millimetres, not metres
    assert [t["line"] for t in doc["targets"]] == list(range(2, 27))


def test_joints_replace_the_pose_columns_in_place() -> None:
    world = make_world(4)
    comp = world.compensator()
    Q = world.configurations(5)
    text = "id,x,y,z,rx,ry,rz,q1,q2,q3,q4,q5,q6,note\n" + "".join(
        f"{i},{','.join(repr(float(v)) for v in to_vector(comp.accurate_pose(q)))},"
        f"{','.join(repr(float(v)) for v in q)},\"a, b\"\n" for i, q in enumerate(Q))
    out, summary = compensate_csv(text, "t.csv", comp, CANONICAL_NEAR, joints=True)
    rows = _rows(out)
    assert list(rows[0]) == ["id", "q1", "q2", "q3", "q4", "q5", "q6", "note"]
    for q, row in zip(Q, rows, strict=True):
        got = np.array([float(row[f"q{j}"]) for j in range(1, 7)])
        assert_same_pose(comp.accurate_pose(got), comp.accurate_pose(q))
        assert row["note"] == "a, b"
    assert summary.as_joints == 5


def test_crlf_tables_stay_crlf_and_full_precision_is_kept() -> None:
    world = make_world(5)
    comp = world.compensator()
    T = comp.accurate_pose(world.configurations(1)[0])
    text = "x,y,z,rx,ry,rz\r\n" + ",".join(repr(float(v)) for v in to_vector(T)) + "\r\n"
    out, _ = compensate_csv(text, "t.csv", comp, CANONICAL_NEAR)
    assert out.endswith("\r\n") and out.count("\r\n") == 2
    values = [float(v) for v in out.splitlines()[1].split(",")]
    assert_lands(comp, to_se3(values), np.asarray(CANONICAL_NEAR), T)


@pytest.mark.parametrize(("text", "says"), [
    ("", "t.csv: empty file"),
    ("x,y,z,rx,ry\n1,2,3,4,5\n", "t.csv: line 1: missing column(s) rz"),
    ("x,y,z,rx,ry,rz,q1,q2\n", "t.csv: line 1: joint columns q1,q2 without the rest"),
    ("x,y,z,rx,ry,rz\n0.4,0,0.3,3.1,0,0\n0.4,0,0.3,3.1,0\n", "t.csv: line 3: expected 6 fields, got 5"),
    ("x,y,z,rx,ry,rz\n0.4,abc,0.3,3.1,0,0\n", "t.csv: line 2, column y: 'abc' is not a number"),
    ("x,y,z,rx,ry,rz\n0.4,nan,0.3,3.1,0,0\n", "t.csv: line 2, column y: expected a finite number, got nan"),
    ("x,y,z,rx,ry,rz\n400,0,300,3.1,0,0\n",
     ("t.csv: line 2: position (x, y, z) from the base: its length (target distance) must be in [0, 5] m, "
      "got 500; 500 looks like millimetres")),
    ("x,y,z,rx,ry,rz,q1,q2,q3,q4,q5,q6\n0.4,0,0.3,3.1,0,0,0,0,9,0,0,0\n", "t.csv: line 2, column q3"),
])
def test_bad_tables_are_named_by_line(text: str, says: str) -> None:
    with pytest.raises(InputError) as err:
        compensate_csv(text, "t.csv", make_world(6).compensator(), CANONICAL_NEAR)
    assert str(err.value).startswith(says), err.value


def test_an_unreachable_row_is_named_by_its_line() -> None:
    comp = make_world(7).compensator()
    T = comp.accurate_pose(np.asarray(CANONICAL_NEAR))
    far = pin.SE3(T.rotation, np.array([2.5, 0.0, 0.3]))  # beyond a UR5e's 0.85 m reach
    text = "x,y,z,rx,ry,rz\n" + "\n".join(",".join(repr(float(v)) for v in to_vector(M)) for M in (T, far))
    with pytest.raises(UnreachableError, match=r"^t\.csv: line 3: "):
        compensate_csv(text, "t.csv", comp, CANONICAL_NEAR)


def test_a_csv_is_told_from_a_program_by_its_header() -> None:
    assert looks_like_csv("\nlabel,x,y,z,rx,ry,rz\n1,2")
    assert not looks_like_csv("def prog():\n  movel(p[1,2,3,4,5,6])\nend\n")
