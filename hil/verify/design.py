"""The pose test's joint targets, both modes, checked before anything moves.

The tool is the SMR centre (its offset in the flange frame: the model's, else the configuration's
guess) and keeps one orientation at all five poses, as ISO 9283 asks of a pose test: its axis (the
flange z axis, along which the SMR opens) points from the cube's centre at the tracker, so the tracker
sees every pose within the SMR's acceptance angle. Each pose is a tool pose in the base frame; its
joints are found two ways (`hil.compensation.solve.Compensator`):

* **uncompensated** — the controller's own IK of the pose (its nominal DH plus its factory deltas):
  the joints ``movel(p[...])`` would drive to;
* **compensated** — hil's calibrated model solved for the same pose, on the controller's branch.

The configuration (shoulder, elbow, wrist) and the tool's turn about its axis are searched for the
first that works everywhere: every target inside the joint limits, the SMR inside the keep-in box along
the joint-space path of the cycle, no wrist or elbow near a singularity, the line of sight clear of the
arm (the selector's tests) — preferring the configuration nearest where the arm stands. A cube no
configuration serves is bad input, said in one line naming the cube; nothing is clamped.

The targets are computed once and stored with the verification (`Design.to_dict`), so a resumed test
drives exactly the same joints, whatever pose the arm was left in.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from hil.arm.branches import nominal_branches
from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry, pose
from hil.arm.ik import UnreachableError
from hil.arm.kinematics import Kinematics
from hil.arm.safety import check_target
from hil.compensation.solve import Compensator
from hil.errors import HilError, InputError
from hil.verify.cube import CYCLE_ORDER, POSE_NAMES, Cube, pose_index

UNCOMPENSATED, COMPENSATED = "uncompensated", "compensated"
MODES: tuple[str, ...] = (UNCOMPENSATED, COMPENSATED)

#: |sin q| below this for the elbow (q3) or the middle wrist joint (q5) is too near a singularity: the
#: joints there move fast for small tool motions, and the two models' solutions may part branches.
SINGULARITY_MARGIN = 0.2
#: Turns of the tool about its axis tried (rad): the SMR is symmetric about it, so any turn measures the
#: same; the first that all poses reach is taken, starting from the tool x axis pointing down.
TOOL_TURNS = tuple(math.radians(a) for a in (0, 30, -30, 60, -60, 90, -90, 120, -120, 150, -150, 180))
#: Where the tracker is taken to stand when only the start pose tells (m along the SMR's axis): the
#: operator locked the beam on it there, so the axis points at the tracker; a laser tracker in a robot
#: cell stands 2–4 m away (`hil.calibration.synthetic.random_truth`), the direction is what matters.
ASSUMED_TRACKER_DISTANCE = 3.0
#: Range of the shoulder lift q2 (rad): the upper arm at or above the horizontal, as the campaign's own
#: poses (`hil.campaign.chooser.CAMPAIGN_UPPER`), so no move between poses swings it through the floor.
UPRIGHT = (-math.pi, 0.0)


@dataclass(frozen=True)
class Visit:
    """One measured visit of the test: the `index`-th of the whole sequence (1-based)."""

    index: int
    cycle: int  # 0-based
    mode: str
    pose: str  # P1..P5
    q: np.ndarray


@dataclass(frozen=True)
class Design:
    """What the test drives to: cube, tool, its orientation and the joints of every pose and mode."""

    robot: str
    cube: Cube
    tool: np.ndarray  # SMR centre in the flange frame (m): the TCP of every target
    rotation: np.ndarray  # (3, 3) the tool's orientation in the base frame, the same for all poses
    tracker: np.ndarray  # (3,) the tracker position the tool faces (base frame, m)
    tracker_source: str  # "model", "configuration" or "start pose" (see ASSUMED_TRACKER_DISTANCE)
    modes: tuple[str, ...]
    cycles: int
    joints: Mapping[str, np.ndarray]  # mode -> (5, 6) joints of P1..P5

    def positions(self) -> np.ndarray:
        """(5, 3) commanded SMR positions of P1..P5 in the base frame."""
        return self.cube.poses()

    def target(self, pose: str) -> pin.SE3:
        """The tool pose of `pose` (base frame)."""
        return pin.SE3(np.asarray(self.rotation), self.positions()[pose_index(pose)])

    def visits(self) -> list[Visit]:
        """Every visit in order: per cycle, each mode's P1, P5, P4, P3, P2 (ISO 9283's cycle).

        The modes alternate cycle by cycle rather than running 30 cycles each: a slow drift (the arm
        warming up) then weighs on both alike, and every pose is still approached from the same side
        each time — P1 of the compensated cycle comes from the uncompensated P2, millimetres from
        where its own P2 is.
        """
        out = []
        for cycle in range(self.cycles):
            for mode in self.modes:
                for name in CYCLE_ORDER:
                    out.append(Visit(len(out) + 1, cycle, mode, name,
                                     np.asarray(self.joints[mode][pose_index(name)])))
        return out

    def lead_in(self, visit: Visit) -> np.ndarray:
        """The joints the arm should come from to approach `visit` as in an unbroken sequence: the
        previous visit's, and for the first one the last pose of a cycle (P2 of the last mode)."""
        visits = self.visits()
        return visits[visit.index - 2].q if visit.index > 1 else visits[len(self.modes) * 5 - 1].q

    def to_dict(self) -> dict[str, Any]:
        return {"robot": self.robot, "cube": self.cube.to_dict(), "tool": [float(v) for v in self.tool],
                "rotation": np.asarray(self.rotation, float).tolist(),
                "tracker": [float(v) for v in self.tracker], "tracker_source": self.tracker_source,
                "modes": list(self.modes), "cycles": self.cycles,
                "joints": {m: np.asarray(q, float).tolist() for m, q in self.joints.items()}}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Design:
        return cls(str(data["robot"]), Cube.from_dict(data["cube"]), np.asarray(data["tool"], float),
                   np.asarray(data["rotation"], float), np.asarray(data["tracker"], float),
                   str(data["tracker_source"]), tuple(data["modes"]), int(data["cycles"]),
                   {m: np.asarray(q, float) for m, q in data["joints"].items()})


def facing(direction: np.ndarray, turn: float = 0.0) -> np.ndarray:
    """A rotation whose z axis is `direction`, its x axis the downward vertical's projection turned by
    `turn` about z (the world x axis' when the tool points straight up or down)."""
    z = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    down = np.array([0.0, 0.0, -1.0])
    x = down - (down @ z) * z
    if np.linalg.norm(x) < 1e-6:
        x = np.array([1.0, 0.0, 0.0]) - z[0] * z
    x /= np.linalg.norm(x)
    R = np.column_stack([x, np.cross(z, x), z])
    return R @ pin.rpy.rpyToMatrix(0.0, 0.0, turn)


def tracker_from_start(controller: Geometry, tool: np.ndarray, start: np.ndarray) -> np.ndarray:
    """Where the tracker stands, from the start pose alone: along the SMR's axis (see
    `ASSUMED_TRACKER_DISTANCE`), by the controller's model."""
    F = Kinematics(controller).flange_poses(np.asarray(start, float))[0]
    smr = F[:3, :3] @ np.asarray(tool, float) + F[:3, 3]
    return smr + ASSUMED_TRACKER_DISTANCE * F[:3, 2]


#: The default cube, as fractions of the datasheet reach: its centre this far out from the base axis
#: and this high above the base, its edge. Chosen on simulated stations (UR3e, UR5e, UR10e, trackers
#: 2-4 m away in every direction, tests/hil/verify/test_design.py): nearer the base, the near poses put
#: the wrist over the base axis once the SMR faces outwards; so the cube serves 29 of 30 random cells.
DEFAULT_CUBE = {"radius": 0.7, "height": 0.3, "edge": 0.25}
#: Turns of the default cube about the base axis tried when the arm would block the beam at the first
#: (rad): the cube stays on the tracker's side.
DEFAULT_CUBE_TURNS = (0.0, math.radians(25), math.radians(-25))


def default_cube(robot: str, tracker: np.ndarray, turn: float = 0.0) -> Cube:
    """The cube of a station that names none (``--sim``): in front of the arm, towards the tracker.

    `DEFAULT_CUBE` says where (0.595 m out, 0.255 m up, edge 0.212 m for a UR5e); `turn` moves it about
    the base axis. ISO 9283 asks for the largest cube of the most used part of the working space, which
    only the cell's owner knows: a station names its cube in ``[verify]``.
    """
    spec = get_robot(robot)
    t = np.asarray(tracker, dtype=float)
    heading = (math.atan2(t[1], t[0]) if math.hypot(t[0], t[1]) > 1e-6 else 0.0) + turn
    r = DEFAULT_CUBE["radius"] * spec.reach
    return Cube(np.array([r * math.cos(heading), r * math.sin(heading), DEFAULT_CUBE["height"] * spec.reach]),
                round(DEFAULT_CUBE["edge"] * spec.reach, 3))


def check_cube(robot: str, cube: Cube, tool: np.ndarray, keep_in: tuple[np.ndarray, np.ndarray],
               where: str) -> None:
    """Refuse, before connecting, a cube the SMR cannot reach or that leaves the keep-in box.

    The SMR's positions are the poses themselves, so the box is checked on them directly; the reach is
    the datasheet's from the shoulder (joint 2's axis at height d1), plus the tool's length.
    """
    spec = get_robot(robot)
    shoulder = np.array([0.0, 0.0, spec.dh.d[0]])
    limit = spec.reach + float(np.linalg.norm(tool))
    lo, hi = (np.asarray(v, float) for v in keep_in)
    for name, p in zip(POSE_NAMES, cube.poses(), strict=True):
        far = float(np.linalg.norm(p - shoulder))
        if far > limit:
            raise InputError(f"{where}: {name} at {np.round(p, 3).tolist()} m is {far:.3f} m from the "
                             f"shoulder, beyond a {spec.title}'s reach ({spec.reach:g} m)")
        if np.any(p < lo) or np.any(p > hi):
            raise InputError(f"{where}: {name} at {np.round(p, 3).tolist()} m is outside the keep-in box "
                             f"{lo.tolist()}..{hi.tolist()}")


#: m: the beam is checked for the arm from this far in front of the SMR. The selector's 3 cm
#: (`selector.candidates.Constraints.beam_clearance`) suits poses facing the tracker anyhow; here the tool
#: axis points straight at it, so the first 10 cm of the beam lie in front of the SMR, and the wrist's
#: enveloping capsule (6 cm for a UR10e) would otherwise swallow the beam's start for an SMR close to
#: the flange and call every pose hidden.
BEAM_CLEARANCE = 0.10


class _Sight:
    """The selector's acceptance and line-of-sight tests for one tracker position, built once
    (`hil.calibration.selection.hidden_reason` asks the same, one pose at a time)."""

    def __init__(self, robot: str, tool: np.ndarray, tracker: np.ndarray, acceptance_angle: float) -> None:
        from hil.calibration.selection import RECHECK_MARGIN_DEG, SelectionModel
        from selector.candidates import CONSTRAINT_NAMES, Constraints

        names = ("acceptance", "line-of-sight")
        self.model = SelectionModel(robot, tool, tracker)
        self.constraints = Constraints(tracker=tuple(map(float, tracker)),
                                       half_angle_deg=max(1.0, acceptance_angle - RECHECK_MARGIN_DEG),
                                       beam_clearance=BEAM_CLEARANCE,
                                       disabled=frozenset(CONSTRAINT_NAMES) - set(names))

    def hidden(self, q: np.ndarray) -> str | None:
        """Why the tracker would not see the SMR at one of the configurations `q` (N, 6), or None."""
        from selector.candidates import evaluate

        passes, _ = evaluate(self.model, np.atleast_2d(q), self.constraints)
        if not np.all(passes["acceptance"]):
            limit = self.constraints.half_angle_deg
            return f"the SMR would face away from the tracker (more than {limit:.0f}°)"
        if not np.all(passes["line-of-sight"]):
            return "the arm would block the tracker's line of sight"
        return None


class _Rejected(HilError):
    """A candidate configuration that does not serve every pose (why, for the operator)."""


def design_test(compensator: Compensator, cube: Cube, tool: np.ndarray, tracker: np.ndarray, *,
                tracker_source: str, modes: Sequence[str], cycles: int,
                keep_in: tuple[np.ndarray, np.ndarray], acceptance_angle: float,
                start: np.ndarray | None = None, where: str = "the test cube") -> Design:
    """The joints of every pose and mode (see the module docstring); InputError naming `where` when no
    configuration serves the cube.

    `compensator` holds hil's model and the controller's, its TCP the `tool`; with one mode only
    (no model: ``UNCOMPENSATED``) its accurate model may be the controller's own.
    """
    robot = compensator.controller.robot
    spec = get_robot(robot)
    check_model = Geometry.nominal(spec, tool)
    sight = _Sight(robot, np.asarray(tool, float), np.asarray(tracker, float), acceptance_angle)
    tcp_inv = pose(np.asarray(tool, float)).inverse()
    direction = np.asarray(tracker, float) - cube.centre
    positions = cube.poses()
    order = [pose_index(p) for p in CYCLE_ORDER]
    first_problem: str | None = None
    for turn in TOOL_TURNS:
        R = facing(direction, turn)
        targets = [pin.SE3(R, positions[i]) for i in order]
        found: list[tuple[float, dict[str, np.ndarray]]] = []
        branches = nominal_branches(robot, targets[0] * tcp_inv)
        if not branches:
            first_problem = first_problem or "P1 is beyond the arm's reach"
        for seed in branches:
            try:
                first = compensator.controller_joints(targets[0], seed)
                if not UPRIGHT[0] <= first[1] <= UPRIGHT[1]:
                    raise _Rejected("P1: the upper arm would point below the horizontal")
                joints = _solve_cycle(compensator, targets, first, modes)
                _check(joints, spec, keep_in, check_model, sight)
            except (_Rejected, UnreachableError, InputError) as exc:
                first_problem = first_problem or str(exc)
                continue
            distance = 0.0 if start is None else float(np.max(np.abs(first - np.asarray(start))))
            found.append((distance, joints))
        if found:
            _, joints = min(found, key=lambda f: f[0])  # nearest where the arm stands
            return Design(robot, cube, np.asarray(tool, float), R, np.asarray(tracker, float),
                          tracker_source, tuple(modes), int(cycles), joints)
    raise InputError(f"{where} (centre {np.round(cube.centre, 3).tolist()} m, edge {cube.edge:g} m): no arm "
                     f"configuration reaches all five poses with the SMR facing the tracker "
                     f"({first_problem or 'no IK solution'}); move or shrink the cube")


def _solve_cycle(compensator: Compensator, targets: list[pin.SE3], first: np.ndarray,
                 modes: Sequence[str]) -> dict[str, np.ndarray]:
    """(5, 6) joints per mode in P1..P5 order, each pose seeded by the previous one of the cycle."""
    solved = compensator.solve_all(targets, first, where=list(CYCLE_ORDER))
    out = {}
    for mode in modes:
        q = np.empty((5, 6))
        for name, c in zip(CYCLE_ORDER, solved, strict=True):
            q[pose_index(name)] = c.q_controller if mode == UNCOMPENSATED else c.q
        out[mode] = q
    return out


def _check(joints: Mapping[str, np.ndarray], spec: Any, keep_in: tuple[np.ndarray, np.ndarray],
           check_model: Geometry, sight: _Sight) -> None:
    """Raise `_Rejected`/InputError unless every target and the cycle's paths are safe and seen."""
    for mode, q in joints.items():
        if np.any(np.abs(np.sin(q[:, 2])) < SINGULARITY_MARGIN) or \
                np.any(np.abs(np.sin(q[:, 4])) < SINGULARITY_MARGIN):
            raise _Rejected(f"{mode}: the elbow or the wrist is near a singularity")
        if np.any(q[:, 1] < UPRIGHT[0]) or np.any(q[:, 1] > UPRIGHT[1]):
            raise _Rejected(f"{mode}: the upper arm would point below the horizontal")
        previous = None
        for name in (*CYCLE_ORDER, CYCLE_ORDER[0]):  # the cycle's moves, back to P1
            target = q[pose_index(name)]
            check_target(target, spec, keep_in, check_model, previous)
            previous = target
        reason = sight.hidden(q)
        if reason is not None:
            raise _Rejected(f"{mode}: {reason}")
