"""How well the arm followed the path: ISO 9283-style figures, and how much of the path they cover.

* Path accuracy AT: for every measured point during the motion, its distance to the commanded path
  (the dense commanded polyline); max and RMS of those.
* Corner deviation: for every interior program point, its distance to the measured path (and, for
  reference, to the commanded one: the bridge keeps that within E by design).
* Corner resolution: the measured path between two tracker records is a straight chord, so a corner
  between two records far apart along the path is cut by the chord whatever the arm did. For every
  corner, the commanded path's largest distance from the chord joining it at the two measured records
  around the corner says how far the measured figure can be off for that reason alone (a 10 Hz
  stream on a 150 mm/s path puts records 15 mm apart: a blended corner is then not resolved).
* Coverage: the tracker loses the SMR when the beam is blocked or the SMR turns away, and a figure
  over the first fifth of a path says nothing of the rest. Each tracker record (measured or lost)
  is placed on the path by its time stamp; the stretch between two consecutive *measured* records
  is covered, the rest is not. A corner outside every covered stretch gets no measured deviation
  (``null``) rather than its distance to wherever the measured points happen to be.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial import cKDTree


def project_onto_path(points: np.ndarray, path: np.ndarray,
                      path_s: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(distance of each point to the polyline `path`, arc length of its nearest point on it).

    The nearest vertex, then the exact foot on its two segments; the arc length (with `path_s`, the
    vertices' arc lengths; else zeros) is the foot's, not the vertex's, so a figure built on it is not
    off by half the polyline's spacing."""
    _, idx = cKDTree(path).query(points)
    best = np.full(len(points), np.inf)
    where = np.zeros(len(points))
    for off in (-1, 0):
        j = np.clip(idx + off, 0, len(path) - 2)
        a, b = path[j], path[j + 1]
        ab = b - a
        t = np.clip(np.einsum("ij,ij->i", points - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab),
                                                                        1e-300), 0.0, 1.0)
        d = np.linalg.norm(points - (a + t[:, None] * ab), axis=1)
        closer = d < best
        best = np.where(closer, d, best)
        if path_s is not None:
            where = np.where(closer, path_s[j] + t * (path_s[j + 1] - path_s[j]), where)
    return best, where


def distance_to_path(points: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Distance of each point to the polyline `path` (nearest vertex, then its two segments)."""
    return project_onto_path(points, path)[0]


@dataclass(frozen=True)
class Coverage:
    """The stretches of the path (arc length, mm) between consecutive measured tracker records."""

    spans: np.ndarray  # (K, 2) [from, to] mm
    length: float  # mm, the whole path

    @property
    def fraction(self) -> float:
        if not self.length:
            return 0.0
        return float(min(np.sum(self.spans[:, 1] - self.spans[:, 0]) / self.length, 1.0))

    def covers(self, s: np.ndarray) -> np.ndarray:
        """Whether each arc length lies in a covered stretch."""
        s = np.asarray(s, float)
        return np.any((self.spans[None, :, 0] <= s[:, None]) & (s[:, None] <= self.spans[None, :, 1]), axis=1)

    @property
    def largest_gap(self) -> tuple[float, float]:
        """The longest uncovered stretch (from, to) in mm."""
        edges = np.r_[0.0, self.spans.ravel(), self.length].reshape(-1, 2)  # [gap start, gap end] rows
        k = int(np.argmax(edges[:, 1] - edges[:, 0]))
        return float(edges[k, 0]), float(edges[k, 1])


def coverage(s: np.ndarray, measured: np.ndarray, length: float) -> Coverage:
    """Coverage from the records' arc lengths `s` (time order) and whether each was measured."""
    s = np.asarray(s, float)
    ok = np.asarray(measured, bool)
    both = ok[1:] & ok[:-1] & (np.diff(s) >= 0)
    spans = np.column_stack([s[:-1][both], s[1:][both]]) if len(s) > 1 else np.zeros((0, 2))
    return Coverage(spans.reshape(-1, 2), float(length))


def corner_resolution(path: np.ndarray, path_s: np.ndarray, measured_s: np.ndarray,
                      corner_s: np.ndarray) -> list[float | None]:
    """For each corner (its arc length), how far the commanded path strays from the chord between the
    measured records just before and after it (mm); None where no measured record lies on one side.

    `path` is the dense commanded polyline with arc lengths `path_s`; `measured_s` the arc lengths of
    the measured records. This is the error the polyline of the records adds to the corner figure.
    """
    order = np.sort(np.asarray(measured_s, float))
    out: list[float | None] = []
    for cs in np.asarray(corner_s, float):
        k = int(np.searchsorted(order, cs, side="right"))
        if k == 0 or k == len(order):
            out.append(None)
            continue
        a, b = order[k - 1], order[k]
        pa = np.array([np.interp(a, path_s, path[:, i]) for i in range(path.shape[1])])
        pb = np.array([np.interp(b, path_s, path[:, i]) for i in range(path.shape[1])])
        inside = path[(path_s >= a) & (path_s <= b)]
        out.append(float(distance_to_path(inside, np.vstack([pa, pb])).max()) if len(inside) else 0.0)
    return out


def path_accuracy(commanded: np.ndarray, measured: np.ndarray, corners: np.ndarray,
                  corner_covered: np.ndarray | None = None, covered: float | None = None,
                  commanded_s: np.ndarray | None = None) -> dict[str, Any]:
    """ISO 9283-style figures in mm (module docstring); a corner not covered has no measured value.

    With the commanded polyline's arc lengths `commanded_s`, each corner's resolution too: the
    measured points are placed on the path by where they are (the foot of each on the commanded path,
    `project_onto_path`), not by their time stamps, so a late or early stamp cannot pick the wrong two
    points around a corner; and by the exact foot, not the nearest commanded sample, so a corner's
    measured figure stays within its commanded one plus the largest deviation plus this resolution.
    """
    dev, measured_s = project_onto_path(measured, commanded, commanded_s)
    resolution: list[float | None] | None = None
    if commanded_s is not None and len(corners):
        resolution = corner_resolution(commanded, commanded_s, measured_s,
                                       project_onto_path(corners, commanded, commanded_s)[1])
    at_corner: list[float | None] = []
    if len(corners) and len(measured) > 1:
        at_corner = distance_to_path(corners, measured).tolist()
        if corner_covered is not None:
            at_corner = [d if c else None for d, c in zip(at_corner, corner_covered, strict=True)]
            if resolution is not None:
                resolution = [r if c else None for r, c in zip(resolution, corner_covered, strict=True)]
    return {"samples": len(measured), "coverage": covered,
            "max_deviation_mm": float(dev.max()), "rms_deviation_mm": float(np.sqrt(np.mean(dev ** 2))),
            "corner_deviation_measured_mm": at_corner,
            "corner_resolution_mm": resolution if resolution is not None else [None] * len(at_corner),
            "corner_deviation_commanded_mm": distance_to_path(corners, commanded).tolist()
            if len(corners) else []}
