"""Choosing measurement poses: observability indices, candidates, tabu search, bounds. Pure functions.

The package implements method 000 (see ``shared/seeds/README.md``): the identification Jacobian of the
identifiable parameters is stacked over the chosen poses and an observability index of it is maximised
by an outer loop of random restarts around a tabu search, with redundant-pose removal. Around it:

* `indices` — O1…O5 and column scaling;
* `information` — the information matrix of a pose set with low-rank (determinant lemma) swap scores;
* `design` — what every method shares (the `Selection` result, count checks, scoring, redundancy);
* `tabu` — the patent method; `exchange` — the DETMAX baseline; `random_selection` — the naive one;
  `search` — the one entry point that picks a method by name;
* `bound` — the D-optimal approximate-design bound (multiplicative algorithm with a duality certificate);
* `candidates` / `arm` — feasible configurations under joint, workspace, visibility, singularity and
  self-collision constraints;
* `order` — the visiting order that minimises travel time;
* `motion_time` — a move's time under the driver's movej profile; `time_aware` — poses and their tour
  chosen together for the least robot time at a target accuracy (or the best accuracy in a budget);
* `cluster_sample` — validation poses as a two-stage cluster sample (unbiased, far less travel).

Nothing here does I/O or imports `hil`: the kinematic model arrives as an argument satisfying
`selector.model.PoseModel`. Modules import each other one way (errors, indices, information, design,
then the methods, then search); none imports this package's face.
"""

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from selector.bound import Bound, d_optimal_bound
    from selector.candidates import CandidateSet, Constraints, generate_candidates
    from selector.cluster_sample import ClusterSample, cluster_sample, cluster_standard_error, design_effect
    from selector.design import Selection, minimum_poses
    from selector.errors import CountError, NoCandidatesError, SelectorError, UnknownIndexError
    from selector.exchange import exchange_select
    from selector.indices import INDEX_NAMES, observability, parse_index
    from selector.motion_time import Dwell, MotionProfile
    from selector.order import order_poses, travel_time
    from selector.random_selection import random_select
    from selector.search import select
    from selector.tabu import TabuSettings, tabu_select
    from selector.time_aware import TimedSelection, time_aware_select

#: Each public name by the module that defines it, imported when first asked for: a command that needs
#: one module's names (`hil select --help` its constraint, index and method names) does not load scipy's
#: linear algebra and clustering through every other module (0.46 s of `hil select --help`'s 0.5 s).
_LAZY = {
    **dict.fromkeys(("Bound", "d_optimal_bound"), "selector.bound"),
    **dict.fromkeys(("CandidateSet", "Constraints", "generate_candidates"), "selector.candidates"),
    **dict.fromkeys(("ClusterSample", "cluster_sample", "cluster_standard_error", "design_effect"),
                    "selector.cluster_sample"),
    **dict.fromkeys(("Selection", "minimum_poses"), "selector.design"),
    **dict.fromkeys(("CountError", "NoCandidatesError", "SelectorError", "UnknownIndexError"),
                    "selector.errors"),
    **dict.fromkeys(("exchange_select",), "selector.exchange"),
    **dict.fromkeys(("INDEX_NAMES", "observability", "parse_index"), "selector.indices"),
    **dict.fromkeys(("Dwell", "MotionProfile"), "selector.motion_time"),
    **dict.fromkeys(("order_poses", "travel_time"), "selector.order"),
    **dict.fromkeys(("random_select",), "selector.random_selection"),
    **dict.fromkeys(("select",), "selector.search"),
    **dict.fromkeys(("TabuSettings", "tabu_select"), "selector.tabu"),
    **dict.fromkeys(("TimedSelection", "time_aware_select"), "selector.time_aware"),
}


def __getattr__(name: str) -> object:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


__all__ = [
    "INDEX_NAMES",
    "Bound",
    "CandidateSet",
    "ClusterSample",
    "Constraints",
    "CountError",
    "Dwell",
    "MotionProfile",
    "NoCandidatesError",
    "Selection",
    "SelectorError",
    "TabuSettings",
    "TimedSelection",
    "UnknownIndexError",
    "cluster_sample",
    "cluster_standard_error",
    "d_optimal_bound",
    "design_effect",
    "exchange_select",
    "generate_candidates",
    "minimum_poses",
    "observability",
    "order_poses",
    "parse_index",
    "random_select",
    "select",
    "tabu_select",
    "time_aware_select",
    "travel_time",
]
