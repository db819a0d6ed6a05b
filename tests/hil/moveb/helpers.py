"""Checks of the MOVEB guarantees on dense samples, shared by the tests and the benchmark."""

from __future__ import annotations

import numpy as np

from hil.moveb.path_plan import Plan


def distance_to_polyline(points: np.ndarray, vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(distance of each point to the polyline, index of the nearest segment)."""
    a, b = vertices[:-1], vertices[1:]
    ab = b - a
    best = np.full(len(points), np.inf)
    seg = np.zeros(len(points), int)
    for j in range(len(a)):  # tests use modest programs
        t = np.clip((points - a[j]) @ ab[j] / (ab[j] @ ab[j]), 0.0, 1.0)
        d = np.linalg.norm(points - (a[j] + t[:, None] * ab[j]), axis=1)
        better = d < best
        best[better], seg[better] = d[better], j
    return best, seg


def point_errors(plan: Plan, step: float = 0.02) -> np.ndarray:
    """Distance from each original point to the densely sampled curve."""
    dense = plan.dense(step, per_bridge=400).position
    a, ab = dense[:-1], np.diff(dense, axis=0)
    ab2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    out = np.empty(len(plan.program.points))
    for i, p in enumerate(plan.program.positions):  # exact distance to every dense segment
        t = np.clip(np.einsum("ij,ij->i", p - a, ab) / ab2, 0.0, 1.0)
        out[i] = np.linalg.norm(p - (a + t[:, None] * ab), axis=1).min()
    return out
