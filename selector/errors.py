"""Errors the selector raises on purpose.

The selector must not import `hil`, so it has its own `ValueError` subclasses; the glue in
``hil.calibration.selection`` turns them into ``hil.errors.InputError`` (exit code 2 on the command line).
"""

from __future__ import annotations


class SelectorError(ValueError):
    """A request the selector cannot satisfy (bad count, unknown index, no candidates…)."""


class UnknownIndexError(SelectorError):
    """An observability index name that is not O1…O5."""


class CountError(SelectorError):
    """A pose count too small to identify the parameters, or larger than the candidate set."""


class NoCandidatesError(SelectorError):
    """The constraints left no (or too few) candidate configurations; `constraint` names the one that
    removed the most on its own, so a caller can name the setting behind it."""

    def __init__(self, message: str, constraint: str | None = None) -> None:
        super().__init__(message)
        self.constraint = constraint
