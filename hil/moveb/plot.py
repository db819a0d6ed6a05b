"""The figure of a MOVEB run: commanded and measured path, and the deviation along the path.

An engineer judging a run wants to *see* where the arm left the path: whether the error is spread
evenly (a kinematic error), grows in the corners (servo lag, too much speed) or jumps (a lost beam).
So: the path seen along the normal of its best-fit plane (paths are mostly planar: seams, contours),
with the measured points coloured by their deviation, and the deviation against the commanded arc
length with the programmed corners marked. Drawn with the report's matplotlib helpers (Agg canvas,
no pyplot state).
"""

from __future__ import annotations

import numpy as np
from matplotlib.colors import Normalize

from hil.files.outputs import atomic_write_bytes
from hil.report.plots import _figure, _style, png


def _plane_axes(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centre and two in-plane unit axes of the best-fit plane (the two largest principal axes)."""
    centre = points.mean(axis=0)
    _u, _s, Vt = np.linalg.svd(points - centre, full_matrices=False)
    return centre, Vt[0], Vt[1]


def run_figure(path: np.ndarray, path_s: np.ndarray, measured: np.ndarray, deviation: np.ndarray,
               corners: np.ndarray, title: str) -> bytes:
    """PNG bytes: (top) path and measured points in the path's plane, (bottom) deviation along s.

    `path` (M, 3) mm with arc lengths `path_s`; `measured` (N, 3) mm in the same frame with their
    `deviation` (N,) mm; `corners` (K, 3) the programmed interior points.
    """
    fig = _figure(7.5)
    top, bottom = fig.subplots(2, 1, height_ratios=[3, 2])
    centre, u, v = _plane_axes(path)

    def flat(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return (p - centre) @ u, (p - centre) @ v

    norm = Normalize(0.0, max(float(deviation.max()), 1e-6))
    top.plot(*flat(path), color="#444b55", linewidth=0.8, label="commanded")
    sc = top.scatter(*flat(measured), c=deviation, s=3, cmap="viridis", norm=norm, label="measured")
    if len(corners):
        top.scatter(*flat(corners), marker="+", color="#d62728", s=40, label="programmed corner")
    top.set_aspect("equal", adjustable="datalim")
    top.set_xlabel("mm (path plane)", fontsize=8)
    top.set_ylabel("mm", fontsize=8)
    top.legend(fontsize=7, loc="best")
    top.set_title(title, fontsize=9)
    fig.colorbar(sc, ax=top, label="deviation (mm)", shrink=0.8)
    _style(top)
    # deviation along the path: each measured point at the arc length of its nearest path sample
    nearest = np.argmin(np.linalg.norm(measured[:, None, :] - path[None, ::4, :], axis=2), axis=1) * 4 \
        if len(path) * len(measured) < 4e7 else np.zeros(len(measured), int)
    order = np.argsort(path_s[nearest])
    bottom.plot(path_s[nearest][order], deviation[order], color="#1f6fb4", linewidth=0.8)
    if len(corners):
        at = path_s[np.argmin(np.linalg.norm(corners[:, None, :] - path[None], axis=2), axis=1)]
        for s in at:
            bottom.axvline(s, color="#d62728", linewidth=0.6, linestyle=":")
    bottom.set_xlabel("arc length along the commanded path (mm); dotted: programmed corners", fontsize=8)
    bottom.set_ylabel("deviation (mm)", fontsize=8)
    _style(bottom)
    return png(fig)


def write_run_figure(out: str, *args: object, **kwargs: object) -> None:
    """`run_figure` written atomically to `out`."""
    atomic_write_bytes(out, run_figure(*args, **kwargs))  # type: ignore[arg-type]
