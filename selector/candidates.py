"""Candidate measurement configurations: random joint vectors that pass every enabled constraint.

Joint vectors are drawn uniformly (seeded) inside the joint limits intersected with ±π per joint (the
kinematics are 2π-periodic, so wider ranges add no information, only travel and cable wrap; set
`Constraints.joint_lower/joint_upper` to narrow further), except q5, which is drawn uniformly over the
values that point the SMR at the tracker (`aim_wrist`). Each batch goes through the constraints in
cascade, cheap ones first; survivors are kept until `count` candidates are found or `max_samples` were
drawn. A request that geometry alone shows to be empty (a tracker inside the base, a keep-in box out
of reach…: `impossible`) is refused before any draw. When nothing survives, every constraint is
evaluated on its own on a fresh batch so that the error can name the one that removes the most.

Constraints (`Constraints.disabled` switches any of them off by name):

* ``keep-in`` — the SMR centre inside the user's box (base frame);
* ``floor`` — no link capsule below the mounting surface (base and shoulder excepted);
* ``range`` — tracker-to-SMR distance within [min, max];
* ``acceptance`` — the angle between the SMR's opening axis (flange z unless configured) and the line
  to the tracker at most the half-angle (30° default: a standard 1.5" SMR);
* ``line-of-sight`` — the beam (from `beam_clearance` beyond the SMR to the tracker) clears every link
  capsule except the tool's own;
* ``wrist`` / ``elbow`` / ``shoulder`` — at least the configured distance from each singularity;
* ``self-collision`` — no two non-adjacent capsules closer than `collision_margin`.

The tracker constraints need the tracker's position; with `tracker=None` they are off (and reported
so), since a selection without a known station layout is still useful for simulation.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from selector.arm import (
    COLLISION_MARGIN,
    elbow_measure,
    segment_distance,
    shoulder_measure,
    wrist_measure,
)
from selector.errors import NoCandidatesError, SelectorError
from selector.feasibility import impossible
from selector.model import PoseModel
from selector.names import CONSTRAINT_NAMES

TRACKER_CONSTRAINTS: frozenset[str] = frozenset({"range", "acceptance", "line-of-sight"})


@dataclass(frozen=True)
class Constraints:
    """Settings of every candidate constraint (metres, degrees where named so)."""

    tracker: tuple[float, float, float] | None = None  # tracker position in the base frame
    keep_in_lower: tuple[float, float, float] = (-10.0, -10.0, 0.0)
    keep_in_upper: tuple[float, float, float] = (10.0, 10.0, 10.0)
    floor: float = 0.0  # z of the mounting surface
    tracker_range: tuple[float, float] = (0.8, 20.0)
    half_angle_deg: float = 30.0
    opening_axis: tuple[float, float, float] = (0.0, 0.0, 1.0)  # in the flange frame
    beam_clearance: float = 0.03  # the beam is checked from this far beyond the SMR centre
    wrist_margin_deg: float = 10.0
    elbow_margin_deg: float = 10.0
    shoulder_margin: float = 0.05
    collision_margin: float = COLLISION_MARGIN
    joint_lower: tuple[float, ...] | None = None
    joint_upper: tuple[float, ...] | None = None
    disabled: frozenset[str] = field(default_factory=frozenset)

    def __post_init__(self) -> None:
        unknown = sorted(set(self.disabled) - set(CONSTRAINT_NAMES))
        if unknown:
            raise SelectorError(f"unknown constraint(s) {', '.join(unknown)}: choose from "
                                f"{', '.join(CONSTRAINT_NAMES)}")
        lo, hi = np.asarray(self.keep_in_lower, float), np.asarray(self.keep_in_upper, float)
        if lo.shape != (3,) or hi.shape != (3,) or np.any(lo >= hi):
            raise SelectorError("keep-in box: every lower bound must be below its upper bound")
        rmin, rmax = self.tracker_range
        if not 0.0 <= rmin < rmax:
            raise SelectorError(f"tracker range must satisfy 0 ≤ min < max, got {rmin}, {rmax}")
        if not 0.0 < self.half_angle_deg <= 180.0:
            raise SelectorError(
                f"acceptance half-angle must be in (0, 180] degrees, got {self.half_angle_deg}")
        if not (0.0 <= self.wrist_margin_deg < 90.0 and 0.0 <= self.elbow_margin_deg < 90.0):
            raise SelectorError("singularity margins must be in [0, 90) degrees")
        if self.shoulder_margin < 0 or self.collision_margin < 0 or self.beam_clearance < 0:
            raise SelectorError("margins and clearances must not be negative")
        if np.linalg.norm(self.opening_axis) == 0:
            raise SelectorError("the SMR opening axis must not be zero")

    def enabled(self) -> tuple[str, ...]:
        """Names of the constraints actually applied (tracker ones need a tracker position)."""
        return tuple(c for c in CONSTRAINT_NAMES if c not in self.disabled
                     and not (c in TRACKER_CONSTRAINTS and self.tracker is None))

    def as_dict(self) -> dict[str, object]:
        """Plain settings for reports (what the JSON output calls 'constraints')."""
        return {
            "enabled": list(self.enabled()),
            "disabled": sorted(set(CONSTRAINT_NAMES) - set(self.enabled())),
            "tracker": None if self.tracker is None else [float(v) for v in self.tracker],
            "keep_in": {"lower": list(map(float, self.keep_in_lower)),
                        "upper": list(map(float, self.keep_in_upper))},
            "floor": self.floor, "tracker_range": list(map(float, self.tracker_range)),
            "half_angle_deg": self.half_angle_deg, "opening_axis": list(map(float, self.opening_axis)),
            "beam_clearance": self.beam_clearance, "wrist_margin_deg": self.wrist_margin_deg,
            "elbow_margin_deg": self.elbow_margin_deg, "shoulder_margin": self.shoulder_margin,
            "collision_margin": self.collision_margin,
        }


@dataclass(frozen=True)
class CandidateSet:
    """Feasible configurations, their SMR positions and identification Jacobians."""

    q: np.ndarray  # (N, n joints)
    smr: np.ndarray  # (N, 3) SMR centres, base frame
    jacobian: np.ndarray  # (N, 3, n)
    sampled: int  # joint vectors drawn
    rejected: dict[str, int]  # per constraint: draws it rejected (applied cheap first, in cascade)
    seconds: float

    def __len__(self) -> int:
        return len(self.q)


def sampling_box(model: PoseModel, constraints: Constraints) -> tuple[np.ndarray, np.ndarray]:
    """Joint sampling range: the limits ∩ one turn ∩ the user's joint range.

    A joint that turns a full turn or more within its limits is drawn over one turn, ±π where the
    limits allow it (every UR joint: its limits are ±2π, the elbow's ±π), else the turn nearest zero
    inside them; a joint with less than a turn keeps its limits as they are (a Kinova's joint 2 lies
    between 0.82 and 5.46 rad: clipping it to ±π would lose half its range)."""
    lower, upper = np.asarray(model.lower, float), np.asarray(model.upper, float)
    turn = upper - lower >= 2 * math.pi
    centre = np.clip(0.0, lower + math.pi, upper - math.pi)
    lo = np.where(turn, np.maximum(lower, centre - math.pi), lower)
    hi = np.where(turn, np.minimum(upper, centre + math.pi), upper)
    if constraints.joint_lower is not None:
        lo = np.maximum(lo, np.asarray(constraints.joint_lower, float))
    if constraints.joint_upper is not None:
        hi = np.minimum(hi, np.asarray(constraints.joint_upper, float))
    if np.any(lo >= hi):
        bad = [f"q{j + 1}" for j in np.flatnonzero(lo >= hi)]
        raise SelectorError(f"empty joint range for {', '.join(bad)} (inside the joint limits)")
    return lo, hi


#: Order in which the constraints are applied when cascading: cheap ones first.
_CASCADE: tuple[str, ...] = (
    "keep-in", "range", "acceptance", "wrist", "elbow", "shoulder", "floor", "self-collision",
    "line-of-sight",
)
#: The same for a model with its own self-collision check (`PoseModel.collides`, a URDF's meshes:
#: hundreds of microseconds a posture), which then goes last.
_CASCADE_OWN_COLLISION: tuple[str, ...] = (*(c for c in _CASCADE if c != "self-collision"),
                                           "self-collision")
#: The constraints measured on a UR's structure (`selector.arm`'s wrist, elbow and shoulder measures).
UR_SINGULARITIES: frozenset[str] = frozenset({"wrist", "elbow", "shoulder"})


def cascade_order(model: PoseModel) -> tuple[str, ...]:
    """The order the constraints are applied in for `model` (cheap first)."""
    return _CASCADE_OWN_COLLISION if getattr(model, "collides", None) is not None else _CASCADE


def evaluate(model: PoseModel, q: np.ndarray, constraints: Constraints, *, cascade: bool = False
             ) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Per-constraint pass masks for configurations `q`, and the SMR positions (base frame).

    Independent (default): every enabled constraint is evaluated on every configuration, so the masks
    say what each constraint alone rejects. Cascading: each is evaluated only on the survivors of the
    ones before it (cheap first, `_CASCADE`), and a mask is False also where it was not evaluated.
    """
    c = constraints
    enabled = set(c.enabled())
    if not getattr(model.arm, "ur_singularities", True) and enabled & UR_SINGULARITIES:
        raise SelectorError(f"the {', '.join(sorted(enabled & UR_SINGULARITIES))} singularity measures are "
                            "a UR's: disable them for this arm")
    own_collision = getattr(model, "collides", None)
    n = len(q)
    F = model.frames(q)
    R, t = F[:, -1, :3, :3], F[:, -1, :3, 3]
    smr = np.einsum("nij,j->ni", R, np.asarray(model.smr, float)) + t
    radii = np.asarray(model.arm.radii)
    tracker = None if c.tracker is None else np.asarray(c.tracker, float)
    alive = np.ones(n, dtype=bool)
    passes: dict[str, np.ndarray] = {}
    segs: np.ndarray | None = None
    for name in cascade_order(model):
        if name not in enabled:
            continue
        rows = np.flatnonzero(alive) if cascade else np.arange(n)
        Fi, si = F[rows], smr[rows]
        if name in ("floor", "line-of-sight") or (name == "self-collision" and own_collision is None):
            segs_i = model.arm.segments(Fi, si) if (cascade or segs is None) else segs
            if not cascade:
                segs = segs_i
        if name in TRACKER_CONSTRAINTS:
            assert tracker is not None
            beam = tracker - si
            dist = np.linalg.norm(beam, axis=1)
            u = beam / np.where(dist > 0, dist, 1.0)[:, None]
        if name == "keep-in":
            ok = np.all((si >= c.keep_in_lower) & (si <= c.keep_in_upper), axis=1)
        elif name == "floor":
            first = model.arm.floor_from  # capsules before it stand on the mounting surface
            low = np.min(segs_i[:, first:, :, 2], axis=2) - radii[first:]
            ok = np.all(low >= c.floor, axis=1)
        elif name == "range":
            ok = (dist >= c.tracker_range[0]) & (dist <= c.tracker_range[1])
        elif name == "acceptance":
            axis = np.asarray(c.opening_axis, float)
            axis = Fi[:, -1, :3, :3] @ (axis / np.linalg.norm(axis))
            ok = np.einsum("ni,ni->n", axis, u) >= math.cos(math.radians(c.half_angle_deg))
        elif name == "line-of-sight":
            start = si + u * np.minimum(c.beam_clearance, dist)[:, None]
            links = segs_i[:, :-1]  # every capsule but the tool's own
            d = segment_distance(start[:, None], np.broadcast_to(tracker, start.shape)[:, None],
                                         links[:, :, 0], links[:, :, 1])
            ok = np.all(d > radii[:-1], axis=1)
        elif name == "wrist":
            ok = wrist_measure(Fi) >= math.sin(math.radians(c.wrist_margin_deg))
        elif name == "elbow":
            ok = elbow_measure(Fi) >= math.sin(math.radians(c.elbow_margin_deg))
        elif name == "shoulder":
            ok = shoulder_measure(Fi) >= c.shoulder_margin
        elif own_collision is not None:  # self-collision by the model's own check
            ok = ~np.asarray(own_collision(q[rows]), dtype=bool)
        else:  # self-collision
            ok = model.arm.collision_free(segs_i, c.collision_margin)
        mask = np.zeros(n, dtype=bool)
        mask[rows] = ok
        passes[name] = mask
        if cascade:
            alive &= mask
    return passes, smr


def aim_wrist(model: PoseModel, q: np.ndarray, constraints: Constraints, rng: np.random.Generator
              ) -> np.ndarray:
    """`q` with q5 (`PoseModel.aim_joint`'s joint: q5 on a UR) redrawn uniformly over the values that
    point the SMR at the tracker.

    Uniform joint sampling wastes over 90 % of its draws on an SMR facing away from the tracker. For
    fixed q1–q4 and q6 the opening axis is a(q5) = A·cos q5 + B·sin q5 + C (joint 5 rotates about the z
    axis of its frame, `PoseModel.frames`' convention), so a(q5)·u ≥ cos θ holds on an interval of q5
    around the best value, which is where q5 is drawn (u, the direction to the tracker, is taken at the
    original q5; the exact check afterwards removes those that the wrist's own motion pushes out).
    Rows with no such interval keep their q5 and fail the acceptance check. The rest of the distribution
    stays uniform.
    """
    centre, half, ok = aim_interval(model, q, constraints)
    k = aim_joint(model)
    q5 = centre + half * (2.0 * rng.random(len(q)) - 1.0)
    out = q.copy()
    out[ok, k] = np.angle(np.exp(1j * q5[ok]))  # wrap to (−π, π]
    return out


def aim_interval(model: PoseModel, q: np.ndarray, constraints: Constraints
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For each row of `q`, the values of `aim_joint`'s joint that point the SMR at the tracker within
    the acceptance half-angle, the others held (`aim_wrist`'s derivation): (centre, half-width, ok), the
    interval centre ± half-width (rad, centre unwrapped), ok False where no value does."""
    c = constraints
    tracker = np.asarray(c.tracker, float)
    axis = np.asarray(c.opening_axis, float)
    axis = axis / np.linalg.norm(axis)
    k = aim_joint(model)
    assert k is not None
    F = model.frames(q)
    R6 = F[:, -1, :3, :3]
    smr = np.einsum("nij,j->ni", R6, np.asarray(model.smr, float)) + F[:, -1, :3, 3]
    u = tracker - smr
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    # The axis in joint 5's rotated frame is fixed; rotating by δ about that frame's z gives
    # a(δ) = cos δ·R5[vx, vy, 0] + sin δ·R5[−vy, vx, 0] + R5[0, 0, vz], with δ = q5' − q5.
    R5 = F[:, k, :3, :3]
    v = np.einsum("nji,nj->ni", R5, R6 @ axis)
    zero = np.zeros(len(q))
    A = np.einsum("nij,nj->ni", R5, np.stack([v[:, 0], v[:, 1], zero], 1))
    B = np.einsum("nij,nj->ni", R5, np.stack([-v[:, 1], v[:, 0], zero], 1))
    C = np.einsum("nij,nj->ni", R5, np.stack([zero, zero, v[:, 2]], 1))
    ua, ub, uc = (np.einsum("ni,ni->n", u, V) for V in (A, B, C))
    rho, phi = np.hypot(ua, ub), np.arctan2(ub, ua) + q[:, k]
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = (math.cos(math.radians(c.half_angle_deg)) - uc) / rho
    ok = ratio <= 1.0
    half = np.arccos(np.clip(ratio, -1.0, 1.0))
    return phi, half, ok


def aim_joint(model: PoseModel) -> int | None:
    """The revolute joint `aim_wrist` turns to face the SMR to the tracker: `PoseModel.aim_joint` when
    the model says (None: none), else joint 5 (index 4), a UR's."""
    return getattr(model, "aim_joint", 4)


def generate_candidates(model: PoseModel, count: int, constraints: Constraints | None = None, *,
                        seed: int = 0, max_samples: int | None = None, batch: int = 8192) -> CandidateSet:
    """Up to `count` feasible configurations (deterministic for `seed`), with their Jacobians.

    Draws at most `max_samples` (default 100·count) joint vectors. Raises NoCandidatesError before
    drawing when geometry proves a constraint cannot pass (`impossible`), and when none passes, naming
    the constraint that rejected the most draws; with no survivor the draws stop at a bound of their
    own (`hopeless`), however many candidates were asked for. Fewer than `count` survivors are
    returned as they are; the caller decides whether that is enough.
    """
    t0 = time.perf_counter()
    constraints = constraints or Constraints()
    if count < 1:
        raise SelectorError(f"candidate count must be at least 1, got {count}")
    max_samples = max_samples or max(100 * count, 10_000)
    lo, hi = sampling_box(model, constraints)
    rng = np.random.default_rng(seed)
    rejected = dict.fromkeys(constraints.enabled(), 0)
    kept_q: list[np.ndarray] = []
    kept_smr: list[np.ndarray] = []
    found = sampled = 0
    rate = 0.5  # acceptance guess until the first batch tells
    hopeless = max(10 * batch, 50_000)  # draws without a single survivor after which we give up
    dof = len(lo)
    k = aim_joint(model)
    aim = ("acceptance" in constraints.enabled() and k is not None and hi[k] - lo[k] >= 2 * math.pi - 1e-9)
    proof = impossible(model, constraints, lo, hi)
    if proof is not None:
        worst, why = proof
        raise NoCandidatesError(f"no candidate configuration satisfies the constraints: '{worst}' cannot "
                                f"pass: {why}; relax or disable it", worst)
    while found < count and sampled < max_samples and not (found == 0 and sampled >= hopeless):
        size = int(min(max_samples - sampled, max(batch, 1.2 * (count - found) / max(rate, 1e-3))))
        if found == 0:  # a guess from no survivors is no guess: never draw past `hopeless` on it
            size = min(size, max(batch, hopeless - sampled))
        q = lo + (hi - lo) * rng.random((size, dof))
        if aim:
            q = aim_wrist(model, q, constraints, rng)
        passes, smr = evaluate(model, q, constraints, cascade=True)
        ok = np.ones(size, dtype=bool)
        for name in cascade_order(model):
            if name in passes:
                rejected[name] += int(np.sum(ok & ~passes[name]))
                ok &= passes[name]
        sampled += size
        found += int(ok.sum())
        rate = max(found / sampled, 1e-4)
        kept_q.append(q[ok])
        kept_smr.append(smr[ok])
    Q = np.concatenate(kept_q)[:count]
    if len(Q) == 0:
        # Rank the constraints by what each rejects on its own, on a fresh sample.
        q = lo + (hi - lo) * rng.random((min(batch, max_samples), dof))
        if aim:
            q = aim_wrist(model, q, constraints, rng)
        alone = {k: int(np.sum(~v)) for k, v in evaluate(model, q, constraints)[0].items()}
        worst = max(alone, key=lambda k: alone[k]) if alone else "joint range"
        raise NoCandidatesError(
            f"no candidate configuration satisfies the constraints ({sampled} drawn): '{worst}' removed "
            f"the most ({alone.get(worst, 0)} of {len(q)} on its own); relax or disable it", worst)
    S = np.concatenate(kept_smr)[:count]
    G = np.asarray(model.jacobian(Q), dtype=float)
    return CandidateSet(Q, S, G, sampled, rejected, time.perf_counter() - t0)
