"""Glue between hil's kinematic model and the `selector` package (which never imports hil).

`SelectionModel` adapts a nominal `Geometry` to `selector.model.PoseModel`; `select_poses` runs the
whole pipeline (candidates → selection → bound → visiting order) and returns the JSON-ready report
that ``hil select`` writes. Every `selector.SelectorError` becomes an `InputError` here, so the CLI
answers bad requests with one line and exit code 2.

Choices made here:

* **Geometry.** The nominal geometry of the robot with the user's SMR offset, and the tracker at the
  user's position (`look_at_tracker`) or, without one, 2.5 m in front of the robot; the tracker pose only
  reparametrises the tracker columns, which leaves O1 unchanged.
* **Parameters.** hil's identifiable set (27 for a UR). If the SMR guess lies on the joint-6 axis one
  of them is truly unobservable for *this* station; it is dropped (pivoted QR) and named in the report,
  rather than making every design look singular.
* **Expected error magnitudes** (column scaling "expected" for O2–O5): 0.5 mm and 1 mrad for joint and
  flange placements (the synthetic truths' σ), 1 mm for the SMR offset and the tracker position,
  1 mrad for the tracker orientation.
* **Compliance** (``compliance=True``, the campaign's default): the joints whose compliance the
  arm's gravity torques make identifiable (for the payload and mounting) join the parameters, so the
  poses are chosen to separate the sag from the geometry too; their expected magnitude is the typical
  strain-wave compliance (`hil.arm.physical.typical_compliance`).
* **Joint errors** (``joint_errors``, orders): the harmonics of those orders of every joint
  (`hil.arm.kinematics.identifiable_joint_errors`) join the parameters, so the chosen poses spread each
  joint's angle over its turn — a harmonic is only seen where its joint takes different angles. Their
  expected magnitude is `hil.calibration.selection_parameters.JOINT_ERROR_MAGNITUDE`. Lost motion is
  not designed for: the campaign approaches every pose from one side, which makes it a constant the
  geometry holds.
* **Link thickness** scales with the upper-arm length: (|a2| / 0.425)^0.6 times a UR5e's
  (`hil.arm.self_collision.arm_shape`, the capsules the campaign's routes are checked with too).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

import selector
from hil.arm.catalog import get_robot
from hil.arm.chain import Chain, Robot
from hil.arm.geometry import Geometry, look_at_tracker
from hil.arm.joint_error_columns import harmonic_index
from hil.arm.kinematics import (
    EXTENDED_PARAMETER_NAMES,
    Kinematics,
    identifiable_joint_errors,
    identifiable_parameters,
    identifiable_with_compliance,
    refuse_non_ur,
)
from hil.arm.self_collision import arm_shape
from hil.calibration.selection_parameters import drop_unobservable, expected_magnitude
from hil.calibration.urdf_selection import NON_UR_DISABLED, UrdfSelectionModel
from hil.errors import InputError
from selector.bound import d_optimal_bound
from selector.candidates import (
    CONSTRAINT_NAMES,
    Constraints,
    aim_interval,
    aim_joint,
    evaluate,
    generate_candidates,
)
from selector.design import check_count
from selector.indices import SCALINGS, parse_index, scale_columns
from selector.order import order_poses, travel_time
from selector.search import METHODS, select
from selector.tabu import TabuSettings

DEFAULT_TRACKER_FOR_JACOBIAN = (2.5, 0.0, 0.5)
FORMAT = "hil-poses/1"


class SelectionModel:
    """`selector.model.PoseModel` for one arm + SMR + tracker (module docstring for the choices)."""

    def __init__(self, robot: str, smr: Sequence[float] = (0.0, 0.0, 0.045),
                 tracker: Sequence[float] | None = None, *, compliance: bool = False,
                 payload: Any = None, gravity: Sequence[float] | None = None,
                 joint_errors: Sequence[int] = ()) -> None:
        self.spec = get_robot(robot)
        position = DEFAULT_TRACKER_FOR_JACOBIAN if tracker is None else tracker
        self.geometry = Geometry.nominal(self.spec, smr=np.asarray(smr, float),
                                         tracker=look_at_tracker(position))
        self.compliance = compliance
        self.joint_errors = tuple(sorted(set(int(k) for k in joint_errors)))
        self.geometry.payload = payload
        if gravity is not None:
            self.geometry.gravity = np.asarray(gravity, dtype=float)
        self.kinematics = Kinematics(self.geometry)
        self.lower, self.upper = self.spec.lower.copy(), self.spec.upper.copy()
        self.max_joint_speed = self.spec.max_joint_speed.copy()
        self.smr = self.geometry.smr.copy()
        self.arm = arm_shape(self.spec.name)
        self._origins = np.array([M.homogeneous for M in self.geometry.joints])
        self._flange = self.geometry.flange.homogeneous
        self.parameters, self.unobservable = self._observable_parameters()
        self.parameter_names = tuple(EXTENDED_PARAMETER_NAMES[i] for i in self.parameters)
        self.parameter_scale = np.array([expected_magnitude(n, self.spec.name)
                                         for n in self.parameter_names])

    def _observable_parameters(self) -> tuple[np.ndarray, list[str]]:
        if self.compliance:
            idx = identifiable_with_compliance(self.spec.name, self.geometry.payload, self.geometry.gravity)
        else:
            idx = identifiable_parameters(self.spec.name)
        if self.joint_errors:
            free = set(identifiable_joint_errors(self.spec.name, self.compliance, self.geometry.payload,
                                                 self.geometry.gravity).tolist())
            wanted = [harmonic_index(j, k, kind) for j in range(6) for k in self.joint_errors
                      for kind in ("cos", "sin")]
            idx = np.r_[idx, [i for i in wanted if i in free]].astype(int)
        q = np.random.default_rng(11).uniform(-math.pi, math.pi, size=(120, 6))
        return drop_unobservable(self.kinematics, q, idx, EXTENDED_PARAMETER_NAMES)

    def frames(self, q: np.ndarray) -> np.ndarray:
        """(N, 7, 4, 4) joint frames and flange in the base frame.

        Each step is T ← T·origin (one (4N × 4)·(4 × 4) product) then the rotation about z, which
        only mixes the first two columns — far cheaper than N separate 4 × 4 products.
        """
        Q = np.atleast_2d(np.asarray(q, dtype=float))
        n = len(Q)
        out = np.empty((n, 7, 4, 4))
        T = np.broadcast_to(np.eye(4), (n, 4, 4))
        c, s = np.cos(Q), np.sin(Q)
        for j in range(6):
            T = (T.reshape(4 * n, 4) @ self._origins[j]).reshape(n, 4, 4)
            x, y = T[:, :, 0].copy(), T[:, :, 1]
            T[:, :, 0] = c[:, j, None] * x + s[:, j, None] * y
            T[:, :, 1] = c[:, j, None] * y - s[:, j, None] * x
            out[:, j] = T
        out[:, 6] = (T.reshape(4 * n, 4) @ self._flange).reshape(n, 4, 4)
        return out

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """(N, 3, n) identification Jacobian of the observable parameters (hil's pinocchio model)."""
        return self.kinematics.jacobian(q, self.parameters)


def parse_constraints(*, tracker: Sequence[float] | None, disabled: Sequence[str] = (),
                      **settings: Any) -> Constraints:
    """`Constraints` from CLI-style values; a bad value raises InputError."""
    try:
        return Constraints(tracker=None if tracker is None else tuple(map(float, tracker)),
                           disabled=frozenset(disabled), **settings)
    except selector.SelectorError as exc:
        raise InputError(str(exc)) from None


#: The constraints that depend on where the tracker stands (its distance, the SMR's acceptance cone
#: toward it, the line of sight to it): with ``--tracker`` given, that position is the first suspect.
TRACKER_CONSTRAINTS = frozenset({"range", "acceptance", "line-of-sight"})
#: The ``hil select`` option that sets each constraint (for one not about the tracker's position).
CONSTRAINT_OPTIONS = {"range": "--range", "acceptance": "--half-angle", "wrist": "--wrist-margin",
                      "elbow": "--elbow-margin", "shoulder": "--shoulder-margin", "floor": "--floor",
                      "keep-in": "--keep-in"}


def naming_the_option(exc: Exception, constraints: Constraints) -> str:
    """`exc`'s message, led by the option behind the constraint that left no candidates: ``--tracker
    0,0,0`` was refused as "no candidate configuration satisfies the constraints" without naming the
    option that caused it."""
    worst = getattr(exc, "constraint", None)
    if worst in TRACKER_CONSTRAINTS and constraints.tracker is not None:
        where = ",".join(f"{v:g}" for v in constraints.tracker)
        return f"--tracker {where}: {exc} (the tracker's position decides '{worst}'; move it)"
    option = CONSTRAINT_OPTIONS.get(worst or "")
    return f"{option}: {exc}" if option else str(exc)


def selection_model(robot: Robot, smr: Sequence[float], tracker: Sequence[float] | None, *,
                    compliance: bool = False, payload: Any = None, gravity: Sequence[float] | None = None,
                    joint_errors: Sequence[int] = (), urdf_path: str | None = None
                    ) -> SelectionModel | UrdfSelectionModel:
    """The selector's model of `robot`: a UR's `SelectionModel`, or for a chain read from a URDF its
    `UrdfSelectionModel` (`urdf_path`: where the file is, for its meshes); compliance and joint errors
    are a UR's, refused for another arm in one line."""
    if isinstance(robot, Chain) and not robot.is_ur:
        if compliance:
            refuse_non_ur(robot, "compliance")
        if joint_errors:
            refuse_non_ur(robot, "joint errors")
        return UrdfSelectionModel(robot, smr, tracker, urdf_path=urdf_path)
    return SelectionModel(robot.name if isinstance(robot, Chain) else robot, smr, tracker,
                          compliance=compliance, payload=payload, gravity=gravity, joint_errors=joint_errors)


def model_name(model: SelectionModel | UrdfSelectionModel) -> str:
    """The robot's name in reports: the catalog name, or the URDF's robot name."""
    return model.name if isinstance(model, UrdfSelectionModel) else model.spec.name


def constraints_for(model: SelectionModel | UrdfSelectionModel, constraints: Constraints) -> Constraints:
    """`constraints` with the UR singularity margins switched off for an arm that is not a UR
    (`hil.calibration.urdf_selection.NON_UR_DISABLED`)."""
    if isinstance(model, UrdfSelectionModel):
        return dataclasses.replace(constraints, disabled=frozenset(constraints.disabled) | NON_UR_DISABLED)
    return constraints


def design_space(robot: Robot, count: int, *, candidates: int, seed: int, smr: Sequence[float],
                 constraints: Constraints, scaling: str, compliance: bool, payload: Any,
                 gravity: Sequence[float] | None,
                 say: Callable[[str, str], None],
                 joint_errors: Sequence[int] = (),
                 check: Callable[[int], None] | None = None, urdf_path: str | None = None,
                 ) -> tuple[SelectionModel | UrdfSelectionModel, Any, np.ndarray]:
    """The selection model, its feasible candidates and their scaled Jacobian blocks (every method's
    starting point); `selector.SelectorError` for a count the candidates cannot serve. `check(n)`, given
    the parameter count, refuses a request before the candidates are drawn (seconds of work). For an
    arm that is not a UR the UR singularity margins of `constraints` are off (`constraints_for`)."""
    model = selection_model(robot, smr, constraints.tracker, compliance=compliance, payload=payload,
                            gravity=gravity, joint_errors=joint_errors, urdf_path=urdf_path)
    constraints = constraints_for(model, constraints)
    n = len(model.parameters)
    check_count(count, candidates, n)
    if check is not None:
        check(n)
    if isinstance(model, UrdfSelectionModel):
        say("self-collision", model.collision.note)
    say("candidates", f"drawing up to {candidates} feasible configurations of the {model_name(model)}")
    cands = generate_candidates(model, candidates, constraints, seed=seed)
    say("candidates", f"{len(cands)} found ({cands.sampled} drawn) in {cands.seconds:.1f} s")
    check_count(count, len(cands), n)
    return model, cands, scale_columns(cands.jacobian, scaling, model.parameter_scale)


def design_fields(model: SelectionModel | UrdfSelectionModel, cands: Any, requested: int, scaling: str,
                  constraints: Constraints) -> dict[str, Any]:
    """The report fields every selection method shares: the parameters, the SMR, the candidates and the
    constraints they met; for an arm from a URDF, the file (name, sha256, base, tip) and how its
    self-collision was checked."""
    constraints = constraints_for(model, constraints)
    extra: dict[str, Any] = {}
    if isinstance(model, UrdfSelectionModel) and model.chain.urdf is not None:
        source = model.chain.urdf
        extra = {"urdf": {"file": source.file, "sha256": source.sha256, "base": source.base,
                          "tip": source.tip},
                 "self_collision": {"check": model.collision.kind, "note": model.collision.note}}
    return {**extra,"parameters": len(model.parameters), "parameter_names": list(model.parameter_names),
            "unobservable": model.unobservable, "scaling": scaling,
            "smr": [float(v) for v in model.smr],
            "candidates": {"requested": requested, "found": len(cands), "sampled": cands.sampled,
                           "rejected": cands.rejected},
            "constraints": constraints.as_dict()}


def select_poses(robot: Robot, count: int, *, candidates: int = 20_000, index: str = "O1",
                 method: str = "tabu", seed: int = 0, smr: Sequence[float] = (0.0, 0.0, 0.045),
                 constraints: Constraints | None = None, scaling: str = "expected",
                 start: Sequence[float] | None = None, settings: TabuSettings | None = None,
                 bound: bool = True, progress: Callable[[str, str], None] | None = None,
                 compliance: bool = False, payload: Any = None,
                 gravity: Sequence[float] | None = None,
                 joint_errors: Sequence[int] = (), urdf_path: str | None = None) -> dict[str, Any]:
    """Choose `count` measurement poses for `robot` (a catalog name, or a chain read from the URDF at
    `urdf_path`); the JSON-ready report (see ``hil select``).

    With `compliance` the identifiable joint compliances (for `payload` and `gravity`) are parameters
    of the design too, and so are the harmonics of the orders `joint_errors` of every joint.

    `progress(phase, text)` hears what is going on ("candidates", "search", "bound", "order"): repeated
    calls with one phase update the same line of a display.
    """
    say = progress or (lambda _phase, _text: None)
    constraints = constraints or Constraints()
    try:
        index = parse_index(index)
        if scaling not in SCALINGS:
            raise selector.SelectorError(f"unknown column scaling {scaling!r}: choose one of "
                                         f"{', '.join(SCALINGS)}")
        if method not in METHODS:
            raise selector.SelectorError(f"unknown method {method!r}: choose one of {', '.join(METHODS)}")
        model, cands, G = design_space(robot, count, candidates=candidates, seed=seed, smr=smr,
                                       constraints=constraints, scaling=scaling, compliance=compliance,
                                       payload=payload, gravity=gravity, say=say,
                                       joint_errors=joint_errors, urdf_path=urdf_path)
        options: dict[str, object] = {"settings": settings} if method == "tabu" and settings else {}
        t0 = time.perf_counter()
        say("search", f"{method} search for {count} poses maximising {index}")
        if method == "tabu":
            options["progress"] = lambda done, total: say(
                "search", f"{method}, restart {done}/{total}, {time.perf_counter() - t0:.1f} s")
        result = select(G, count, method=method, index=index, seed=seed, **options)
        say("search", f"{method}, {index} = {result.value:.4g} in {result.seconds:.1f} s")
        t0 = time.perf_counter()
        if bound:
            say("bound", "the D-optimal bound on O1 (--no-bound skips it)")
            b = d_optimal_bound(G, progress=lambda iterations, gap: say(
                "bound", f"gap {100 * gap:.2f} % (stops at 0.1 %) after {iterations} iterations, "
                         f"{time.perf_counter() - t0:.1f} s"))
            say("bound", f"O1 <= {b.value:.4g}; the selection reaches "
                         f"{100.0 * result.o1 / b.value:.1f} % of it ({time.perf_counter() - t0:.1f} s)")
        else:
            b = None
        bound_seconds = time.perf_counter() - t0
        Q = cands.q[result.chosen]
        if start is not None and len(start) != len(model.lower):
            raise selector.SelectorError(f"--start needs {len(model.lower)} joint values")
        t0 = time.perf_counter()
        perm, ordered = order_poses(Q, model.max_joint_speed, start)
        order_seconds = time.perf_counter() - t0
    except selector.SelectorError as exc:
        raise InputError(naming_the_option(exc, constraints)) from None
    unordered = travel_time(Q, model.max_joint_speed, start)
    report: dict[str, Any] = {
        "format": FORMAT,
        "robot": model_name(model),
        "index": index,
        "value": result.value,
        "o1": result.o1,
        "bound": None if b is None else b.value,
        "bound_index": "O1",
        "percent_of_bound": None if b is None else 100.0 * result.o1 / b.value,
        "bound_gap": None if b is None else b.gap,
        "method": method,
        "seed": seed,
        "seconds": result.seconds,
        "timings": {"candidates": cands.seconds, "selection": result.seconds, "bound": bound_seconds,
                    "order": order_seconds},
        "count": len(Q),
        **design_fields(model, cands, candidates, scaling, constraints),
        "travel_time": {"ordered": ordered, "unordered": unordered,
                        "saved_percent": 100.0 * (1.0 - ordered / unordered) if unordered > 0 else 0.0,
                        "start": None if start is None else [float(v) for v in start],
                        "model": "joint space, slowest joint at its maximum speed"},
        "details": dict(result.details),
        "poses": [[float(v) for v in q] for q in Q[perm]],
    }
    return report


#: Degrees kept from the SMR's acceptance half-angle when a planned pose is checked again during the run.
RECHECK_MARGIN_DEG = 2.0


@functools.lru_cache(maxsize=4)
def _sight_model(robot: str, smr: tuple[float, ...], tracker: tuple[float, ...]) -> SelectionModel:
    """`hidden_reason`'s model, kept: a campaign asks about pose after pose with the same SMR and
    tracker (refitted only every few points, `hil.campaign.calibration_plan._SightCheck`), and building the
    model (its identifiable parameters: a Jacobian of 120 poses and a pivoted QR) took 10-35 ms against the
    check's 3 ms, measured on the simulated station (the check itself only reads it)."""
    return SelectionModel(robot, smr, tracker)


def hidden_reason(robot: str, smr: Sequence[float], tracker: Sequence[float], q: Sequence[float],
                  acceptance_angle: float) -> str | None:
    """Why the tracker would not see the SMR at `q` (None: it would), by the selector's own checks.

    Used during a campaign with the tracker position and SMR offset fitted to the points measured so
    far, which are far better known than when the poses were chosen: the SMR must face the tracker
    within the acceptance half-angle less `RECHECK_MARGIN_DEG`, and the beam must clear the arm's
    enveloping capsules (thicker than the links).
    """
    return hidden_reasons(robot, smr, tracker, np.asarray(q, dtype=float)[None], acceptance_angle)[0]


def hidden_reasons(robot: str, smr: Sequence[float], tracker: Sequence[float], q: np.ndarray,
                   acceptance_angle: float) -> list[str | None]:
    """`hidden_reason` for each row of `q` (n, 6) in one evaluation: a sweep's path is checked at
    dozens of samples a segment, and the selector's checks take all of them at once."""
    model = _sight_model(robot, tuple(map(float, smr)), tuple(map(float, tracker)))
    names = ("acceptance", "line-of-sight")
    constraints = Constraints(tracker=tuple(map(float, tracker)),
                              half_angle_deg=max(1.0, acceptance_angle - RECHECK_MARGIN_DEG),
                              disabled=frozenset(CONSTRAINT_NAMES) - set(names))
    passes, _ = evaluate(model, np.asarray(q, dtype=float).reshape(-1, 6), constraints)
    away = f"the SMR would face away from the tracker (more than {constraints.half_angle_deg:.0f}°)"
    return [away if not facing else "the arm would block the tracker's line of sight" if not clear else None
            for facing, clear in zip(passes["acceptance"], passes["line-of-sight"], strict=True)]


def aimed_vias(robot: str, smr: Sequence[float], tracker: Sequence[float], start: Sequence[float],
               end: Sequence[float], acceptance_angle: float, count: int = 3) -> np.ndarray:
    """`count` via poses (count, 6) between `start` and `end` that turn the wrist to face the SMR to
    the tracker: on the straight joint line, each with the aiming joint (q5 on a UR) at the centre of
    the values that face it (`selector.candidates.aim_interval`), the one nearest the line's.

    Two poses the tracker sees can lie on a straight joint line it does not see along (the SMR turns
    with the wrist on the way); a path through these vias keeps facing it where the wrist can make it."""
    a, b = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    s = np.arange(1, count + 1, dtype=float)[:, None] / (count + 1)
    vias = a + s * (b - a)
    model = _sight_model(robot, tuple(map(float, smr)), tuple(map(float, tracker)))
    constraints = Constraints(tracker=tuple(map(float, tracker)),
                              half_angle_deg=max(1.0, acceptance_angle - RECHECK_MARGIN_DEG))
    centre, _, ok = aim_interval(model, vias, constraints)
    k = aim_joint(model)
    if k is None:
        return vias
    line = vias[:, k]
    vias[ok, k] = (line + np.angle(np.exp(1j * (centre - line))))[ok]  # the equivalent nearest the line
    return vias
