"""The names a user chooses among — search methods, observability indices, column scalings,
constraints — apart from the modules that implement them, so that a command's help lists them
without loading numpy and scipy (`hil select --help`)."""

from __future__ import annotations

#: Search methods, by the name `selector.search.select` dispatches on.
METHODS: tuple[str, ...] = ("tabu", "exchange", "random")
#: Observability indices O1…O5 (`selector.indices`).
INDEX_NAMES: tuple[str, ...] = ("O1", "O2", "O3", "O4", "O5")
#: Column scalings of the identification Jacobian (`selector.indices.scale_columns`).
SCALINGS: tuple[str, ...] = ("expected", "unit", "none")
#: Candidate constraints a user may disable (`selector.candidates.Constraints`).
CONSTRAINT_NAMES: tuple[str, ...] = (
    "keep-in", "floor", "range", "acceptance", "line-of-sight", "wrist", "elbow", "shoulder",
    "self-collision",
)
