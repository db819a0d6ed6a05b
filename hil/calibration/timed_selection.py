"""Time-aware pose selection for a station: `selector.time_aware` on hil's kinematic model.

`select_timed` answers ``hil select --method time-aware`` and the campaign's ``campaign.selection =
"time-aware"``. It draws the same constrained candidates as method 000 (`design_space`), runs method 000
for `count` poses — reported beside, and by default the accuracy to reach — and then chooses poses and
visiting order together (`selector.time_aware.time_aware_select`):

* **target form** (no budget): the expected prediction error of the seed's `count` poses, f = tr(W M⁻¹)
  over the candidates' workspace, reached in the least robot time; the pose count is free;
* **budget form** (`budget` seconds): the lowest f whose tour fits.

Robot time is the driver's movej profile at the station's speed and acceleration
(`selector.motion_time.MotionProfile`) plus a dwell per pose (settling, joint reading, the tracker's
measurement). `fixed` poses (the campaign's validation poses) are visited in the same tour: their time
counts, they inform nothing. Each leg of the tour is checked like the engine checks a move (the SMR
inside the keep-in box along the straight joint path): a leg that would need a detour is counted in
the report (the engine then routes around it, which costs time the prediction does not include).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

import selector
from hil.calibration.selection import FORMAT, design_fields, design_space, naming_the_option
from hil.errors import InputError
from selector.candidates import Constraints
from selector.indices import o1_from_logdet
from selector.motion_time import Dwell, MotionProfile
from selector.order import order_poses
from selector.search import select
from selector.time_aware import TimedSelection, time_aware_select

METHOD = "time-aware"

#: Points checked along each leg of the tour for the keep-in box (as `hil.arm.safety.check_target`).
LEG_CHECKS = 16


def select_timed(robot: str, count: int, *, speed: float, acceleration: float, dwell: Dwell | None = None,
                 budget: float | None = None, fixed: np.ndarray | None = None,
                 start: Sequence[float] | None = None, candidates: int = 20_000, index: str = "O1",
                 seed: int = 0, smr: Sequence[float] = (0.0, 0.0, 0.045),
                 constraints: Constraints | None = None, scaling: str = "expected",
                 compliance: bool = False, payload: Any = None, gravity: Sequence[float] | None = None,
                 joint_errors: Sequence[int] = (), time_limit: float = 5.0,
                 progress: Callable[[str, str], None] | None = None) -> dict[str, Any]:
    """Choose and order poses for the most accuracy per second of robot time (module docstring).

    Returns the JSON-ready ``hil-poses/1`` report: `poses` in visiting order (the fixed poses left out;
    `tour` says where they come), `predicted` for this tour and `seed_method` for method 000's
    `count` poses in their best tour. `joint_errors`: harmonic orders in the design, as
    `hil.calibration.selection.select_poses`.
    """
    say = progress or (lambda _phase, _text: None)
    constraints = constraints or Constraints()
    dwell = dwell or Dwell()
    fixed_count = 0 if fixed is None else len(np.asarray(fixed, dtype=float).reshape(-1, 6))

    def fits(n: int) -> None:
        """Every pose costs at least its dwell: a budget below the fewest poses' dwell is refused before
        the candidates are drawn and searched (it was found only after the search, seconds later)."""
        need = selector.minimum_poses(n)
        least = dwell.seconds * (need + fixed_count)
        if budget is not None and budget < least:
            raise selector.SelectorError(
                f"a budget of {budget:g} s fits fewer than the {need} poses identifying the {n} parameters "
                f"takes: their dwell alone is {least:g} s ({dwell.seconds:g} s a pose)")

    try:
        model, cands, G = design_space(robot, count, candidates=candidates, seed=seed, smr=smr,
                                       constraints=constraints, scaling=scaling, compliance=compliance,
                                       payload=payload, gravity=gravity, say=say,
                                       joint_errors=joint_errors, check=fits)
        profile = MotionProfile(float(speed), float(acceleration), tuple(map(float, model.max_joint_speed)))
        n = len(model.parameters)
        fixed_q = np.zeros((0, 6)) if fixed is None else np.asarray(fixed, dtype=float).reshape(-1, 6)
        start_q = None if start is None else np.asarray(start, dtype=float)
        if start_q is not None and start_q.shape != (6,):
            raise selector.SelectorError("the start needs 6 joint values")
        W = np.einsum("nip,niq->pq", G, G) / len(G)
        t0 = time.perf_counter()
        say("search", f"method 000 (tabu) for {count} poses, the accuracy to match")
        seed_sel = select(G, count, method="tabu", index=index, seed=seed)
        seed_q = cands.q[seed_sel.chosen]
        seed_move = _tour_move_time(seed_q, fixed_q, profile, start_q)
        f_seed = _criterion(G[seed_sel.chosen], W)
        seed_seconds = time.perf_counter() - t0
        form = "budget" if budget is not None else "target"
        say("search", f"time-aware ({form}): poses and order together, {time_limit:g} s")
        result = time_aware_select(
            G, cands.q, profile, dwell.seconds, target=None if budget is not None else f_seed,
            budget=budget, fixed=fixed_q, start=start_q, min_count=selector.minimum_poses(n),
            seed=seed, time_limit=time_limit, workspace=W)
        if len(result.chosen) < selector.minimum_poses(n):
            raise selector.SelectorError(
                f"a budget of {budget:g} s fits only {len(result.chosen)} poses; identifying the {n} "
                f"parameters takes at least {selector.minimum_poses(n)}")
    except selector.SelectorError as exc:
        raise InputError(naming_the_option(exc, constraints)) from None
    chosen_q = cands.q[result.chosen]
    value = float(o1_from_logdet(result.logdet, n, len(result.chosen))) if np.isfinite(result.logdet) else 0.0
    legs = _legs_outside(model, constraints, _tour_q(result, cands.q, fixed_q), start_q)
    seed_time = seed_move + dwell.seconds * (count + len(fixed_q))
    say("search", f"{len(result.chosen)} poses, predicted {result.total_time:.0f} s of robot time "
                  f"(method 000's {count}: {seed_time:.0f} s)")
    return {
        "format": FORMAT,
        "robot": model.spec.name,
        "index": index,
        "value": value if index == "O1" else None,
        "o1": value,
        "bound": None,
        "bound_index": "O1",
        "percent_of_bound": None,
        "method": METHOD,
        "form": form,
        "seed": seed,
        "seconds": result.seconds + seed_seconds,
        "count": len(result.chosen),
        **design_fields(model, cands, candidates, scaling, constraints),
        "motion": profile.as_dict(),
        "dwell": dwell.as_dict(),
        "budget": budget,
        "predicted": _figures(result.criterion, f_seed, result.move_time,
                              dwell.seconds * (len(result.chosen) + len(fixed_q)), len(result.chosen),
                              len(fixed_q)) | {"legs_needing_detour": legs},
        "seed_method": {"method": "tabu", "index": index, "count": int(count), "value": seed_sel.value,
                        "o1": seed_sel.o1, "seconds": seed_seconds,
                        **_figures(f_seed, f_seed, seed_move,
                                   dwell.seconds * (count + len(fixed_q)), count, len(fixed_q))},
        "travel_time": {"ordered": result.move_time, "start": None if start_q is None else start_q.tolist(),
                        "model": "joint space, movej trapezoid of the leading joint (station speed and "
                                 "acceleration)"},
        "details": dict(result.details),
        "tour": [{"role": "selected", "index": int(np.flatnonzero(result.chosen == k)[0])} if k >= 0
                 else {"role": "fixed", "index": int(-1 - k)} for k in result.order],
        "poses": [[float(v) for v in q] for q in chosen_q],
    }


def _criterion(blocks: np.ndarray, W: np.ndarray) -> float:
    B = blocks.reshape(-1, blocks.shape[2])
    return float(np.trace(np.linalg.solve(B.T @ B, W)))


def _figures(f: float, f_seed: float, move: float, dwell: float, poses: int, fixed: int) -> dict[str, Any]:
    return {"criterion": float(f), "relative_error": float(np.sqrt(f / f_seed)), "move_time": float(move),
            "dwell_time": float(dwell), "robot_time": float(move + dwell), "poses": int(poses),
            "fixed_poses": int(fixed)}


def _tour_move_time(Q: np.ndarray, fixed: np.ndarray, profile: MotionProfile,
                    start: np.ndarray | None) -> float:
    """Move time of method 000's poses and the fixed ones in their best single tour."""
    return order_poses(np.vstack([Q, fixed]), profile=profile, start=start)[1]


def _tour_q(result: TimedSelection, Q: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    return np.array([Q[k] if k >= 0 else fixed[-1 - k] for k in result.order]).reshape(-1, 6)


def _legs_outside(model: Any, constraints: Constraints, tour: np.ndarray, start: np.ndarray | None) -> int:
    """Legs of the tour along which the SMR would leave the keep-in box (the engine detours there)."""
    pts = tour if start is None else np.vstack([start[None], tour])
    if len(pts) < 2 or "keep-in" in constraints.disabled:
        return 0
    s = np.linspace(0.0, 1.0, LEG_CHECKS)[None, :, None]
    path = (pts[:-1, None, :] + (pts[1:] - pts[:-1])[:, None, :] * s).reshape(-1, 6)
    p = model.kinematics.points(path, frame="base").reshape(len(pts) - 1, LEG_CHECKS, 3)
    lo, hi = np.asarray(constraints.keep_in_lower), np.asarray(constraints.keep_in_upper)
    return int(np.sum(np.any((p < lo) | (p > hi), axis=(1, 2))))
