"""The campaign's pose chooser: the selector's poses for a station, under the station's constraints.

It turns a `SelectionRequest` of the calibration plan into a `Choice`: calibration poses by the tabu
search of `hil.calibration.selection`, validation poses at random among the same constraints'
candidates. It lives with the campaign because it speaks the plan's request and answer types.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

import selector
from hil.calibration.selection import SelectionModel, hidden_reason, parse_constraints, select_poses
from hil.calibration.timed_selection import select_timed
from hil.campaign.calibration_plan import Choice, SelectionRequest
from hil.campaign.steps import APPROACH, approach_seconds
from hil.errors import InputError
from selector.candidates import Constraints, generate_candidates
from selector.cluster_sample import cluster_sample
from selector.motion_time import Dwell, MotionProfile
from selector.order import order_poses

#: Seconds per pose for reading the joints and the controller's steady check (RTDE at 500 Hz: 10
#: readings are 20 ms; the driver polls the steady state every few milliseconds).
DWELL_OVERHEAD = 0.05

#: Seconds one GeoCOM distance-and-angle reading takes: the simulated instrument's measuring time
#: (`mocks.station`, a tracking-mode EDM reading of a TPS1200-class instrument, about 0.1-0.15 s).
GEOCOM_READING_TIME = 0.1

#: `campaign.selection` of the time-aware selection.
TIME_AWARE = "time-aware"

#: Degrees kept between the selector's acceptance cone and the SMR's own, so poses chosen with an
#: approximate tracker position (a bootstrap estimate) are still visible.
ACCEPTANCE_MARGIN_DEG = 5.0


#: Joint ranges of campaign poses for a floor-mounted arm: the upper arm stays at or above horizontal
#: (q2 in [-π, 0]), so a straight joint-space move between two poses never swings it through the floor.
CAMPAIGN_LOWER = (-math.pi, -math.pi, -math.pi, -math.pi, -math.pi, -math.pi)


CAMPAIGN_UPPER = (math.pi, 0.0, math.pi, math.pi, math.pi, math.pi)


def campaign_chooser(config: Any) -> Any:
    """The campaign's pose chooser (`hil.campaign.calibration_plan.ChoosePoses`) for a station configuration.

    Calibration poses by the tabu search (with the bound, for the report); validation poses at random
    among the same constraints' candidates, with another seed, because validation should sample the
    workspace rather than the poses that are best for the fit.
    """
    from hil.campaign.calibration_plan import CALIBRATION, Choice

    def choose(request: SelectionRequest) -> Choice:
        half = max(1.0, request.acceptance_angle - ACCEPTANCE_MARGIN_DEG)
        constraints = parse_constraints(
            tracker=request.model.tracker.translation, half_angle_deg=half,
            keep_in_lower=tuple(request.keep_in[0]), keep_in_upper=tuple(request.keep_in[1]),
            floor=float(request.keep_in[0][2]), joint_lower=CAMPAIGN_LOWER, joint_upper=CAMPAIGN_UPPER)
        if request.role != CALIBRATION:
            return _validation_poses(config, request, constraints)
        if config.campaign["selection"] == TIME_AWARE:
            return _time_aware(config, request, constraints)
        report = select_poses(
            request.model.robot, request.count, candidates=request.candidates, index=request.index,
            method="tabu", seed=request.seed, smr=request.model.smr, constraints=constraints,
            start=request.start, bound=True, compliance=bool(config.campaign["compliance"]),
            payload=config.payload, gravity=config.gravity,
            joint_errors=_design_orders(config, request.count))
        info = {k: report[k] for k in ("index", "value", "o1", "bound", "percent_of_bound", "method",
                                       "seconds", "travel_time", "candidates", "parameters")}
        return Choice(np.array(report["poses"]), {**info, **_parameter_counts(report, config)})

    # the same line-of-sight and acceptance tests, asked again during the run (`plan._SightCheck`)
    choose.hidden = hidden_reason  # type: ignore[attr-defined]
    if config.campaign["plan_cache"]:  # the same question on every robot of a line: chosen once
        from hil.campaign.plan_cache import cached_chooser

        return cached_chooser(choose, config, config.campaign["plan_cache"])
    return choose


def pose_dwell(config: Any) -> Dwell:
    """The robot time a pose costs besides its move, as the station is configured (for the selector).

    Measuring: ``campaign.samples`` readings, each ``tracker.measure_time`` (emScon's stationary
    measuring time) or, over GeoCOM, `GEOCOM_READING_TIME`. Settling: ``robot.settle_time`` in the fixed
    mode; with ``robot.settle = "stable"`` nothing beyond the readings themselves, since a UR's ring after
    a move at the usual accelerations has died out within the first few readings (`mocks.ringing`) and
    the readings of a ringing arm are still measuring time. Overhead: the joint reading, the
    controller's steady check and the short last leg every visit approaches its pose by
    (``campaign.approach``), the same for every pose.
    """
    reading = (float(config.tracker["measure_time"]) if config.tracker["protocol"] == "emscon"
               else GEOCOM_READING_TIME)
    settle = float(config.robot["settle_time"]) if config.robot["settle"] == "fixed" else 0.0
    approach = approach_seconds(float(config.campaign.get("approach", APPROACH)),
                                float(config.robot["speed"]), float(config.robot["acceleration"]))
    return Dwell(settle=settle, measure=float(config.campaign["samples"]) * reading,
                 overhead=DWELL_OVERHEAD + approach)


def _time_aware(config: Any, request: SelectionRequest, constraints: Constraints) -> Choice:
    """Calibration poses and one tour through them and the validation poses (`request.fixed`)."""
    from hil.campaign.calibration_plan import Choice

    camp = config.campaign
    budget = float(camp["time_budget"]) or None
    report = select_timed(
        request.model.robot, request.count, speed=config.robot["speed"],
        acceleration=config.robot["acceleration"], dwell=pose_dwell(config), budget=budget,
        fixed=request.fixed, start=request.start, candidates=request.candidates, index=request.index,
        seed=request.seed, smr=request.model.smr, constraints=constraints,
        compliance=bool(camp["compliance"]), payload=config.payload, gravity=config.gravity,
        joint_errors=_design_orders(config, request.count), time_limit=float(camp["search_time"]))
    info = {k: report[k] for k in ("index", "value", "o1", "method", "form", "seconds", "travel_time",
                                   "candidates", "parameters", "predicted", "seed_method", "motion",
                                   "dwell", "budget", "tour", "details")}
    return Choice(np.array(report["poses"]), {**info, **_parameter_counts(report, config)})


#: Harmonic parameters one order adds to a design: a cosine and a sine of each of the 6 joints, every
#: one independent of the geometry and compliance on every UR
#: (`hil.arm.kinematics.identifiable_joint_errors`).
HARMONICS_PER_ORDER = 12


def _design_orders(config: Any, count: int | None = None) -> tuple[int, ...]:
    """The joint-error harmonic orders the calibration poses are chosen for (``campaign.joint_errors``).

    Fixed orders: those. "auto" (the default): every candidate order the `count` calibration poses
    (default ``campaign.calibration_poses``) can carry beside the geometry and compliance — an order
    joins only while the poses still identify everything designed so far — so the poses spread each
    joint's angle whatever the fit keeps, and a short campaign (a dozen poses) is chosen for its
    geometry as before, its fit still asking cross-validation which terms the data support.
    """
    from hil.calibration.joint_error_request import parse_request
    from hil.station.config import minimum_calibration_poses
    from selector.design import minimum_poses

    request = parse_request(config.campaign["joint_errors"], "campaign.joint_errors")
    if request.mode != "auto":
        return request.design_orders
    camp = config.campaign
    count = int(camp["calibration_poses"] if count is None else count)
    base = minimum_calibration_poses(config.robot["type"], bool(camp["compliance"]), config.payload,
                                     config.gravity)[1]
    kept: tuple[int, ...] = ()
    for k in request.design_orders:
        if minimum_poses(base + HARMONICS_PER_ORDER * (len(kept) + 1)) > count:
            break
        kept += (k,)
    return kept


def _parameter_counts(report: Mapping[str, Any], config: Any) -> dict[str, Any]:
    """The selection's ``parameters`` are those its SMR guess makes observable; the fit identifies
    them and the ``unobservable`` ones (the same identifiable set, compliance included when
    configured: `hil.station.config.minimum_calibration_poses`): ``identified_parameters`` is the
    fit's count, what a plan is compared with (the model's ``parameters`` once it is fitted). With
    ``campaign.joint_errors = "auto"`` the harmonics the poses were chosen for (``joint_error_design``)
    are not in it: the fit adds those cross-validation keeps, which only the fit knows."""
    from hil.calibration.joint_error_request import parse_request

    unobservable = list(report.get("unobservable") or [])
    designed = sum(1 for name in report.get("parameter_names") or []
                   if name.startswith("joint") and (".cos" in name or ".sin" in name))
    auto = parse_request(config.campaign["joint_errors"], "campaign.joint_errors").mode == "auto"
    identified = int(report["parameters"]) + len(unobservable) - (designed if auto else 0)
    return {"unobservable": unobservable, "joint_error_design": designed,
            "identified_parameters": identified}


def _validation_poses(config: Any, request: Any, constraints: Constraints) -> Any:
    """Validation poses as configured: a simple random sample (``campaign.validation_clusters = 0``) or a
    two-stage cluster sample of the same candidates (`_clustered_poses`)."""
    if int(config.campaign["validation_clusters"]) > 0:
        return _clustered_poses(config, request, constraints)
    return _random_poses(request, constraints)


def _validation_candidates(request: Any, constraints: Constraints) -> tuple[SelectionModel, Any]:
    """The selection model and the constrained candidates validation poses are drawn from."""
    try:
        model = SelectionModel(request.model.robot, request.model.smr, constraints.tracker)
        cands = generate_candidates(model, request.candidates, constraints, seed=request.seed)
    except selector.SelectorError as exc:
        raise InputError(str(exc)) from None
    if len(cands) < request.count:
        raise InputError(f"only {len(cands)} candidate poses satisfy the constraints, "
                         f"{request.count} validation poses asked for")
    return model, cands


def _random_poses(request: Any, constraints: Constraints) -> Any:
    """Validation poses: a random sample of the constrained candidates, in visiting order.

    No minimum count (validation identifies nothing) and no optimisation: validation should sample
    the workspace the robot will work in, not the poses that suit the fit.
    """
    from hil.campaign.calibration_plan import Choice

    model, cands = _validation_candidates(request, constraints)
    rng = np.random.default_rng(request.seed)
    Q = cands.q[rng.choice(len(cands), request.count, replace=False)]
    perm, ordered = order_poses(Q, model.max_joint_speed, request.start)
    return Choice(Q[perm], {"method": "random", "candidates": {"found": len(cands)},
                            "travel_time": {"ordered": ordered}})


def _clustered_poses(config: Any, request: Any, constraints: Constraints) -> Any:
    """Validation poses as a two-stage cluster sample of the constrained candidates, in visiting order.

    Still an unbiased sample of the workspace (every candidate equally likely, `selector.cluster_sample`)
    but in ``campaign.validation_clusters`` groups of nearby poses, so the arm travels far less between
    them. Candidates and seed as `_random_poses`; joints weighted by 1 / their speed in the station's
    movej (`MotionProfile.joint_speeds`), so that "nearby" means "quick to reach". The info's ``labels``
    are the first-stage draw of each pose, in visiting order: the standard error of the validation
    mean square needs them (`selector.cluster_sample.cluster_standard_error`).
    """
    from hil.campaign.calibration_plan import Choice

    model, cands = _validation_candidates(request, constraints)
    speeds = MotionProfile(float(config.robot["speed"]), float(config.robot["acceleration"]),
                           tuple(float(v) for v in model.max_joint_speed)).joint_speeds
    try:
        sample = cluster_sample(cands.q, request.count, int(config.campaign["validation_clusters"]),
                                scale=1.0 / speeds, seed=request.seed)
    except selector.SelectorError as exc:
        raise InputError(f"campaign.validation_clusters: {exc}") from None
    Q = cands.q[sample.indices]
    perm, ordered = order_poses(Q, model.max_joint_speed, request.start)
    return Choice(Q[perm], {"method": "clustered", "clusters": sample.k, "per_cluster": sample.m,
                            "partition": sample.partition, "excluded_fraction": sample.excluded_fraction,
                            "labels": [int(d) for d in sample.draw[perm]],
                            "candidates": {"found": len(cands)}, "travel_time": {"ordered": ordered}})
