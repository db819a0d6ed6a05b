"""Coverage: which stretches of a path the tracker measured, and what a corner outside them gets."""

from __future__ import annotations

import numpy as np
import pytest

from hil.moveb.accuracy import corner_resolution, coverage, path_accuracy


def test_stretches_between_consecutive_measured_records_are_covered() -> None:
    s = np.arange(0.0, 101.0, 1.0)  # a record every mm along a 100 mm path
    ok = np.ones(101, bool)
    ok[40:61] = False  # the beam lost from 40 to 60 mm
    cov = coverage(s, ok, 100.0)
    assert cov.fraction == pytest.approx(0.78)  # 0-39 and 61-100: 39 + 39 mm
    assert cov.largest_gap == (39.0, 61.0)
    assert cov.covers(np.array([10.0, 50.0, 90.0])).tolist() == [True, False, True]


def test_nothing_measured_at_the_ends_is_a_gap() -> None:
    s = np.linspace(20.0, 70.0, 51)
    cov = coverage(s, np.ones(51, bool), 100.0)
    assert cov.fraction == pytest.approx(0.5) and cov.largest_gap == (70.0, 100.0)
    assert coverage(s, np.zeros(51, bool), 100.0).fraction == 0.0


def test_a_corner_outside_the_covered_stretches_has_no_measured_deviation() -> None:
    path = np.c_[np.linspace(0, 100, 1001), np.zeros(1001), np.zeros(1001)]
    measured = path[:300:10] + np.array([0.0, 0.05, 0.0])  # only the first 30 mm
    corners = np.array([[10.0, 0.0, 0.0], [50.0, 0.0, 0.0]])
    acc = path_accuracy(path, measured, corners, corner_covered=np.array([True, False]), covered=0.3)
    assert acc["corner_deviation_measured_mm"][0] == pytest.approx(0.05)
    assert acc["corner_deviation_measured_mm"][1] is None and acc["coverage"] == 0.3
    assert acc["corner_deviation_commanded_mm"] == [0.0, 0.0]


def test_corner_resolution_is_how_far_the_chord_between_the_records_cuts_the_corner() -> None:
    """A right-angle corner at s = 50 mm: records 10 mm either side cut it by 10/√2 mm, records 0.1 mm
    either side by 0.1/√2; a corner with no measured record after it has no resolution."""
    leg = np.linspace(0.0, 50.0, 501)
    path = np.r_[np.c_[leg, 0 * leg, 0 * leg], np.c_[50 + 0 * leg[1:], leg[1:], 0 * leg[1:]]]
    path_s = np.r_[leg, 50.0 + leg[1:]]
    coarse = corner_resolution(path, path_s, np.array([0.0, 40.0, 60.0, 100.0]), np.array([50.0]))
    fine = corner_resolution(path, path_s, np.array([49.9, 50.1]), np.array([50.0]))
    assert coarse[0] == pytest.approx(10 / np.sqrt(2), rel=1e-6)
    assert fine[0] == pytest.approx(0.1 / np.sqrt(2), rel=1e-6)
    assert corner_resolution(path, path_s, np.array([10.0, 40.0]), np.array([50.0])) == [None]
    # the measured points placed on the path by where they are: two points 10 mm either side
    measured = np.array([[0.0, 0.0, 0.0], [40.0, 0.0, 0.0], [50.0, 10.0, 0.0], [50.0, 50.0, 0.0]])
    acc = path_accuracy(path, measured, np.array([[50.0, 0.0, 0.0]]), commanded_s=path_s)
    assert acc["corner_resolution_mm"][0] == pytest.approx(10 / np.sqrt(2), rel=1e-6)
    assert acc["corner_deviation_measured_mm"][0] == pytest.approx(10 / np.sqrt(2), rel=1e-6)
    acc = path_accuracy(path, measured, np.array([[50.0, 0.0, 0.0]]), corner_covered=np.array([False]),
                        commanded_s=path_s)
    assert acc["corner_resolution_mm"] == [None]  # a corner not covered has neither figure
