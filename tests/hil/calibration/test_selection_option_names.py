"""No candidates: the error leads with the option behind the constraint that removed the most, so
``hil select --tracker 0,0,0`` names --tracker as the reason (issue 31)."""

from __future__ import annotations

from types import SimpleNamespace

from hil.calibration.selection import naming_the_option
from selector.errors import NoCandidatesError, SelectorError


def test_a_tracker_constraint_names_the_tracker_when_it_was_given() -> None:
    exc = NoCandidatesError("no candidate configuration satisfies the constraints", "line-of-sight")
    text = naming_the_option(exc, SimpleNamespace(tracker=(0.0, 0.0, 0.0)))
    assert text.startswith("--tracker 0,0,0: no candidate configuration satisfies the constraints")
    assert "'line-of-sight'" in text


def test_without_a_tracker_the_constraint_s_own_option_is_named() -> None:
    exc = NoCandidatesError("no candidate configuration satisfies the constraints", "range")
    assert naming_the_option(exc, SimpleNamespace(tracker=None)).startswith("--range: no candidate")
    exc = NoCandidatesError("no candidate configuration satisfies the constraints", "floor")
    assert naming_the_option(exc, SimpleNamespace(tracker=(1.0, 2.0, 0.5))).startswith("--floor: ")


def test_the_keep_in_box_and_the_shoulder_margin_are_named() -> None:
    exc = NoCandidatesError("no candidate configuration satisfies the constraints", "keep-in")
    assert naming_the_option(exc, SimpleNamespace(tracker=(2.0, 0.0, 0.5))).startswith("--keep-in: ")
    exc = NoCandidatesError("no candidate configuration satisfies the constraints", "shoulder")
    assert naming_the_option(exc, SimpleNamespace(tracker=None)).startswith("--shoulder-margin: ")


def test_other_selector_errors_are_left_as_they_are() -> None:
    none = SimpleNamespace(tracker=None)
    assert naming_the_option(SelectorError("count too small"), none) == "count too small"
    exc = NoCandidatesError("none", "self-collision")  # no option sets it: the message alone
    assert naming_the_option(exc, SimpleNamespace(tracker=None)) == "none"
