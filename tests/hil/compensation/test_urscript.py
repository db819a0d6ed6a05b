"""Compensating URScript programs: real program shapes, every byte outside a rewritten literal kept,
the rewritten values right (parsed back and solved by the controller's model), and what cannot be
compensated listed by line, never dropped."""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import pytest

from hil.arm.ik import UnreachableError, solve_ik
from hil.arm.kinematics import Kinematics
from hil.compensation.poses import CANONICAL_NEAR, to_se3, to_vector
from hil.compensation.solve import Compensator
from hil.compensation.urscript import compensate_program
from hil.errors import InputError
from tests.hil.compensation.world import World, assert_lands, assert_same_pose, make_world


@dataclass(frozen=True)
class Target:
    """A literal of the program the compensation must rewrite."""

    text: str  # as written in the input
    tcp: pin.SE3  # the TCP it is a pose of
    near: np.ndarray  # the joints it was made from (its branch)
    joints: bool = False  # --joints: written as a joint list

    @property
    def wanted(self) -> pin.SE3:
        return to_se3(_numbers(self.text))


Piece = str | Target


def _numbers(literal: str) -> list[float]:
    inner = literal[literal.index("[") + 1:literal.rindex("]")]
    return [float(v) for v in inner.split(",")]


def polyscope(v: float) -> str:
    """Polyscope's spelling: 12 decimals, no leading zero (``-.493910000000``)."""
    return re.sub(r"^(-?)0\.", r"\1.", f"{v:.12f}")


def signed(v: float) -> str:
    """A hand-written spelling: explicit sign, no leading zero (``+.41234``, ``-.1``)."""
    return re.sub(r"^([+-])0\.", r"\1.", f"{v:+.6f}")


def pose_text(M: pin.SE3, spell=polyscope, sep: str = ", ") -> str:
    return "p[" + sep.join(spell(float(v)) for v in to_vector(M)) + "]"


def joints_text(q: np.ndarray, sep: str = ", ") -> str:
    return "[" + sep.join(repr(float(v)) for v in q) + "]"


def build(pieces: Sequence[Piece]) -> str:
    return "".join(p if isinstance(p, str) else p.text for p in pieces)


def rewritten(out: str, pieces: Sequence[Piece]) -> list[str]:
    """The new literals, once every byte between them is proven unchanged: the output must be the
    input's text between the targets, verbatim, with one literal in each target's place."""
    pattern = "".join(re.escape(p) if isinstance(p, str) else r"(p?\[[^\[\]]*\])" for p in pieces)
    m = re.fullmatch(pattern, out, flags=re.DOTALL)
    assert m, "text outside the rewritten literals changed"
    return list(m.groups())


def check(world: World, out: str, pieces: Sequence[Piece]) -> None:
    """Each rewritten literal: a pose the controller's model solves (near the target's branch) to
    joints at which the accurate model puts the tool on the wanted pose; or such joints themselves."""
    targets = [p for p in pieces if isinstance(p, Target)]
    for t, new in zip(targets, rewritten(out, pieces), strict=True):
        comp = world.compensator(t.tcp)
        if t.joints:
            assert not new.startswith("p[")
            assert_same_pose(comp.accurate_pose(np.array(_numbers(new))), t.wanted)
        else:
            assert new.startswith("p[") and new != t.text
            assert_lands(comp, to_se3(_numbers(new)), t.near, t.wanted)


def path(world: World, count: int) -> np.ndarray:
    """Joints along a cell's motion: each a small step from the previous one."""
    steps = world.rng.uniform(-0.15, 0.15, (count, 6))
    return np.asarray(CANONICAL_NEAR) + np.cumsum(steps, axis=0)


FLANGE = pin.SE3.Identity()


def polyscope_program(world: World) -> tuple[list[Piece], np.ndarray]:
    """What Polyscope writes for MoveJ Waypoint_1, MoveL Waypoint_2, a move relative to a feature."""
    comp = world.compensator()
    q1, q2 = path(world, 2)
    w1 = Target(pose_text(comp.accurate_pose(q1)), FLANGE, q1)
    w2 = Target(pose_text(comp.accurate_pose(q2), sep=","), FLANGE, q2)
    return [
        "def Program():\n"
        "  set_standard_analog_input_domain(0, 1)\n"
        "  set_tcp(p[0.0,0.0,0.0,0.0,0.0,0.0])\n"
        "  set_payload(1.0, [0.0, 0.0, 0.0])\n"
        "  global Plane_1=p[.300000000000, -.100000000000, .050000000000, .000000000000, .000000000000, "
        ".000000000000]\n"
        "  global Waypoint_1_p=", w1, "\n"
        f"  global Waypoint_1_q={joints_text(q1)}\n"
        "  global Waypoint_2_p=", w2, "\n"
        f"  global Waypoint_2_q={joints_text(q2, ',')}\n"
        '  $ 1 "Robot Program"\n'
        '  $ 2 "MoveJ"\n'
        '  $ 3 "Waypoint_1" "breakAfter"\n'
        "  movej(get_inverse_kin(Waypoint_1_p, qnear=Waypoint_1_q), a=1.3962634015954636, "
        "v=1.0471975511965976)\n"
        '  $ 4 "MoveL"\n'
        '  $ 5 "Waypoint_2" "breakAfter"\n'
        "  movel(Waypoint_2_p, a=1.2, v=0.25)\n"
        '  $ 6 "MoveL"\n'
        "  movel(pose_trans(Plane_1, p[.0, .0, -.05, .0, .0, .0]), a=1.2, v=0.25)\n"
        '  popup("Done: p[0] reached", "Message", False, False, blocking=True)\n'
        "end\n"], np.array([q1, q2])


def test_a_polyscope_program() -> None:
    world = make_world(11)
    pieces, _ = polyscope_program(world)
    out, summary = compensate_program(build(pieces), "prog.script", world.compensator(), CANONICAL_NEAR)
    check(world, out, pieces)
    assert [(m.line, m.what) for m in summary.moved] == [(6, "Waypoint_1_p"), (8, "Waypoint_2_p")]
    assert [(s.line, s.what) for s in summary.not_compensated] == [(18, "movel")]
    assert "pose_trans(Plane_1, p[.0, .0, -.05, .0, .0, .0]) is computed at run time" in \
        summary.not_compensated[0].reason
    assert [(s.line, s.what) for s in summary.left_alone] == [(5, "Plane_1")]


def test_polyscope_joint_twins_choose_the_branch() -> None:
    """Waypoint_2_q names the other wrist configuration of the same pose: the compensation follows it,
    not the joints the program was at before."""
    world = make_world(12)
    comp = world.compensator()
    q1 = path(world, 1)[0]
    guess = q1 + np.array([0.0, 0.0, 0.0, np.pi, 0.0, np.pi])
    guess[4] = -q1[4]
    flipped = solve_ik(Kinematics(world.truth), comp.accurate_pose(q1), guess, tolerance=1e-13)
    assert np.max(np.abs(flipped - q1)) > 1.0  # one pose, two wrists
    pieces: list[Piece] = [
        f"global Waypoint_1_q={joints_text(q1)}\nmovej(Waypoint_1_q)\n"
        "global Waypoint_2_p=", Target(pose_text(comp.accurate_pose(q1)), FLANGE, flipped), "\n"
        f"global Waypoint_2_q={joints_text(flipped)}\n"
        "movej(get_inverse_kin(Waypoint_2_p, qnear=Waypoint_2_q))\n"]
    out, _ = compensate_program(build(pieces), "prog.script", comp, CANONICAL_NEAR)
    check(world, out, pieces)


def hand_written(world: World) -> list[Piece]:
    """A script written by hand: comments, strings holding p[, a TCP change, movec, a relative move,
    a pose variable, moves known only at run time, CRLF line endings."""
    gripper = to_se3([0, 0, 0.1, 0, 0, 0])
    qs = path(world, 7)
    flange, tool = world.compensator(), world.compensator(gripper)
    a = Target(pose_text(flange.accurate_pose(qs[0]), signed), FLANGE, qs[0], joints=True)
    b = Target(pose_text(tool.accurate_pose(qs[1]), lambda v: f"{v:.6e}", ","), gripper, qs[1], joints=True)
    c = Target(pose_text(tool.accurate_pose(qs[2]), signed), gripper, qs[2], joints=True)
    d = Target(pose_text(tool.accurate_pose(qs[3]), signed), gripper, qs[3], joints=True)
    f = Target(pose_text(tool.accurate_pose(qs[4])), gripper, qs[4])
    g = Target(pose_text(tool.accurate_pose(qs[5]), signed), gripper, qs[5])
    return [
        "# pick and place, written by hand: movel(p[1, 2, 3, 4, 5, 6]) is only a comment\r\n"
        "def pick():\r\n"
        '  textmsg("start: movel(p[1,2,3,4,5,6]) \\" p[")\r\n'
        f"  movej({joints_text(CANONICAL_NEAR)}, a=1.4, v=1.05)\r\n"
        "  movel(", a, ", a=1.2, v=0.25)  # approach, flange TCP\r\n"
        "  set_tcp(p[0, 0, .1, 0, 0, 0])   # gripper: the TCP from here on\r\n"
        "  movel(pose=", b, ",a=1.2,v=0.25)\r\n"
        "  movec(", c, ",\t", d, ", a=1.2, v=0.25, r=0.05)\r\n"
        "  movel(pose_trans(p[.4, -.1, .3, 0, 3.14, 0], p[0, 0, -.05, 0, 0, 0]), a=1.2)\r\n"
        "  local approach = ", f, "\r\n"
        "  movep(approach, a=1.2, v=0.25, r=0.02)\r\n"
        "  movel(pose_add(approach, p[0, 0, .02, 0, 0, 0]))\r\n"
        "  x = get_actual_tcp_pose()\r\n"
        "  movel(x)\r\n"
        "  movel(p[x[0], -.5, +1e-1, 0, 3.14, 0])\r\n"
        "  movej(get_inverse_kin(", g, f", qnear={joints_text(qs[5])}), a=1.4, v=1.05)\r\n"
        "end\r\n"]


@pytest.mark.parametrize("joints", [False, True])
def test_a_hand_written_script(joints: bool) -> None:
    world = make_world(13)
    pieces = hand_written(world)
    if not joints:
        pieces = [p if isinstance(p, str) else Target(p.text, p.tcp, p.near) for p in pieces]
    text = build(pieces)
    out, summary = compensate_program(text, "pick.script", world.compensator(), CANONICAL_NEAR, joints=joints)
    check(world, out, pieces)
    assert out.count("\r\n") == text.count("\r\n") and "\n" not in out.replace("\r\n", "")
    assert [(m.line, m.what) for m in summary.moved] == [
        (5, "movel"), (7, "movel"), (8, "movec"), (8, "movec"), (10, "approach"), (16, "get_inverse_kin")]
    assert [(s.line, s.what) for s in summary.not_compensated] == [
        (9, "movel"), (12, "movel"), (14, "movel"), (15, "movel")]
    reasons = [s.reason for s in summary.not_compensated]
    assert "x is computed at run time (line 13)" in reasons[2]
    assert "holds expressions" in reasons[3]
    assert summary.as_joints == (4 if joints else 0)
    assert summary.left_alone == []


def test_the_tcp_comes_from_the_caller_until_the_program_sets_one() -> None:
    world = make_world(14)
    given = to_se3([0.0, 0.03, 0.08, 0.0, 0.0, 0.2])
    q = path(world, 1)[0]
    t = Target(pose_text(world.compensator(given).accurate_pose(q)), given, q)
    pieces: list[Piece] = ["movel(", t, ")\n"]
    out, _ = compensate_program(build(pieces), "t.script", world.compensator(given), q)
    check(world, out, pieces)


def _skipped(text: str) -> list[tuple[int, str]]:
    world = make_world(15)
    _, summary = compensate_program(text, "t.script", world.compensator(), CANONICAL_NEAR)
    return [(s.line, s.reason) for s in summary.not_compensated]


def test_a_tcp_known_only_at_run_time_stops_compensation_and_says_so() -> None:
    pose = pose_text(make_world(15).compensator().accurate_pose(np.asarray(CANONICAL_NEAR)))
    text = f"t = get_tcp_offset()\nset_tcp(t)\nmovel({pose})\nset_tcp(p[0,0,0,0,0,0])\nmovel({pose})\n"
    assert _skipped(text) == [(3, "the TCP is set at run time (line 2)")]


def test_one_literal_cannot_serve_two_tcps() -> None:
    pose = pose_text(make_world(15).compensator().accurate_pose(np.asarray(CANONICAL_NEAR)))
    text = f"w = {pose}\nmovel(w)\nset_tcp(p[0,0,.1,0,0,0])\nmovel(w)\n"
    skipped = _skipped(text)
    assert [line for line, _ in skipped] == [2, 4]
    assert "different TCPs (lines 2 and 4)" in skipped[0][1]


def test_targets_from_elsewhere_are_listed() -> None:
    text = ("def go(t):\n  movel(t)\nend\nmovej(get_inverse_kin(p[.4,0,.3,0,3.1,0], tcp=my_tcp))\n"
            "movej(get_actual_joint_positions())\nq = [0, -1.5, 1.5, -1.5, -1.5, 0]\nmovej(q)\n")
    assert _skipped(text) == [
        (2, "t is not assigned in this program (a parameter, or set by the installation)"),
        (4, "its tcp argument is computed at run time")]


@pytest.mark.parametrize(("text", "says"), [
    ("x = 1\nmovel(p[.4, 0, .3, 3.1, 0], a=1.2)\n", "t.script:2: movel: p[...] has 5 elements, a pose has 6"),
    ("w = p[.4, 0, .3, 3.1, 0, 0, 1]\n\nmovel(w)\n", "t.script:1: w: p[...] has 7 elements, a pose has 6"),
    ("set_tcp(p[0, 0, .1])\n", "t.script:1: set_tcp: p[...] has 3 elements, a pose has 6"),
    ("def f():\n  movel(p[.4, 0, .3, 3.1, 0, 0)\nend\n", "t.script:2: ')' closes the '[' opened on line 2"),
    ("def f():\n  movel(p[.4, 0, .3, 3.1, 0, 0]\nend\n", "t.script:2: '(' is never closed"),
    ("# a comment\r\n\r\nmovel(p[2.5, 0, .3, 0, 3.14, 0])\r\n", "t.script:3: movel: "),
    ("w = p[0, 0, 3.3, 0, 0, 0]\nmovel(w)\n", "t.script:1: w: "),
])
def test_bad_programs_and_unreachable_targets_name_the_line(text: str, says: str) -> None:
    with pytest.raises(InputError) as err:
        compensate_program(text, "t.script", make_world(16).compensator(), CANONICAL_NEAR)
    assert str(err.value).startswith(says), err.value
    if says.endswith(("movel: ", "w: ")):
        assert isinstance(err.value, UnreachableError)


def test_a_program_without_targets_comes_back_byte_for_byte() -> None:
    text = ('\ufeff# nothing to do\r\ndef f():\n  popup("p[1, 2, 3, 4, 5, 6]")\r\n'
            "  x = pose_inv(p[1,2,3,4,5,6])\nend")
    out, summary = compensate_program(text, "t.script", make_world(17).compensator(), CANONICAL_NEAR)
    assert out == text and summary.moved == [] and summary.not_compensated == []


def test_compensators_are_made_once_per_tcp(monkeypatch: pytest.MonkeyPatch) -> None:
    world = make_world(18)
    made: list[pin.SE3] = []
    real_init = Compensator.__post_init__

    def counting(self: Compensator) -> None:
        made.append(self.tcp)
        real_init(self)

    base = world.compensator()
    monkeypatch.setattr(Compensator, "__post_init__", counting)
    qs = path(world, 4)
    text = "".join(f"movel({pose_text(base.accurate_pose(q))})\n" for q in qs)
    compensate_program(text, "t.script", base, CANONICAL_NEAR)
    assert len(made) == 1
