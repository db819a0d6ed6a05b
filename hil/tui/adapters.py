"""Thin wrappers around helpers of ``hil calibrate`` that the app reuses but that are private there.

The app must build the same ``hil-result/1`` document as the headless command, so it calls the very
same function rather than a copy. (Lead: making `hil.cli.calibrate._result` public would remove this
module.)
"""

from __future__ import annotations

from typing import Any

from hil.config import StationConfig
from hil.events import Event


def result_document(outcome: Any, config: StationConfig, events: list[Event], started: float,
                    truth: dict | None) -> dict[str, Any]:
    """The ``hil-result/1`` document of a run, exactly as ``hil calibrate --out`` writes it."""
    from hil.cli.calibrate import _result

    return _result(outcome, config, events, started, truth)
