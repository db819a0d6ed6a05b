"""Choosing a pose set by method name: the one entry point over tabu, exchange and random selection.

A selection works on candidate Jacobian blocks `G` (N, 3, n), already restricted to the identifiable
parameters and column-scaled (`selector.indices.scale_columns`), and returns indices into them. What
the methods share (the result type, the count check, scoring) is `selector.design`; this module only
dispatches, so it sits above every method and none of them imports it.
"""

from __future__ import annotations

import numpy as np

from selector.design import Selection
from selector.errors import SelectorError
from selector.exchange import exchange_select
from selector.names import METHODS
from selector.random_selection import random_select
from selector.tabu import TabuSettings, tabu_select


def select(G: np.ndarray, count: int, *, method: str = "tabu", index: str = "O1", seed: int = 0,
           **options: object) -> Selection:
    """Dispatch to one method by name ("tabu", "exchange", "random"); options go to that method.

    The ``progress`` option (``progress(done, total)``) is reported by the tabu search and ignored by the
    others (single passes).
    """
    progress = options.pop("progress", None)
    if method == "tabu":
        settings = options.pop("settings", None) or TabuSettings()
        if options:
            raise SelectorError(f"unknown tabu options: {', '.join(sorted(options))}")
        return tabu_select(G, count, index=index, seed=seed, settings=settings,  # type: ignore[arg-type]
                           progress=progress)  # type: ignore[arg-type]
    if options:
        raise SelectorError(f"method {method!r} takes no options ({', '.join(sorted(options))})")
    if method == "exchange":
        return exchange_select(G, count, index=index, seed=seed)
    if method == "random":
        return random_select(G, count, index=index, seed=seed)
    raise SelectorError(f"unknown selection method {method!r}: choose one of {', '.join(METHODS)}")
