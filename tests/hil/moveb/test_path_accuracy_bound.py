"""A corner's measured figure is bounded by what it is made of: the commanded corner deviation, the
largest deviation of a record and the corner's resolution (`hil.moveb.accuracy.path_accuracy`).

The records were placed on the commanded path by their nearest commanded *sample*, not their foot on
it: on a coarse polyline a record just before a corner was placed at the corner, its resolution read
0 and the measured corner figure exceeded the bound (seen by 0.03 µm in a MOVEB run on the dense path,
by 0.35 mm on this coarse one: 0.398 mm measured against a bound of 0.05 mm)."""

from __future__ import annotations

import numpy as np

from hil.moveb.accuracy import path_accuracy, project_onto_path


def _l_path(step: float) -> tuple[np.ndarray, np.ndarray]:
    """An L: along x to (10, 0), then along y to (10, 10), sampled every `step` mm."""
    n = round(10 / step)
    leg1 = np.column_stack([np.linspace(0, 10, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    leg2 = np.column_stack([np.full(n, 10.0), np.linspace(step, 10, n), np.zeros(n)])
    path = np.vstack([leg1, leg2])
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))]
    return path, s


def test_the_corner_figure_stays_within_its_parts_on_a_coarse_path() -> None:
    path, s = _l_path(1.0)
    measured = np.array([[8.6, 0.05, 0.0], [9.6, 0.05, 0.0], [10.05, 1.6, 0.0], [10.05, 2.6, 0.0]])
    corner = np.array([[10.0, 0.0, 0.0]])
    acc = path_accuracy(path, measured, corner, commanded_s=s)
    bound = acc["corner_deviation_commanded_mm"][0] + acc["max_deviation_mm"] + acc["corner_resolution_mm"][0]
    assert acc["corner_deviation_measured_mm"][0] > 0.3  # the records' chord cuts the corner
    assert acc["corner_deviation_measured_mm"][0] <= bound


def test_a_point_is_placed_at_its_foot_on_the_path() -> None:
    path, s = _l_path(1.0)
    d, where = project_onto_path(np.array([[9.6, 0.05, 0.0], [10.05, 1.6, 0.0]]), path, s)
    np.testing.assert_allclose(d, [0.05, 0.05])
    np.testing.assert_allclose(where, [9.6, 11.6])
