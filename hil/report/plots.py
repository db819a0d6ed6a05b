"""The report's figures, drawn with matplotlib and returned as PNG bytes.

Figures are built on `matplotlib.figure.Figure` with the Agg canvas directly, not through pyplot:
no global backend switch, no display needed, nothing kept alive between reports, and safe to call
from the engine's worker thread. User-supplied text (station names…) never goes into a figure, so
nothing here needs escaping (matplotlib would otherwise read ``$…$`` as mathtext).

Lengths are plotted in millimetres. Before-calibration errors are millimetres and after-calibration
errors tens of micrometres, so the per-pose comparison uses a logarithmic axis and the histograms
get one panel each.
"""

from __future__ import annotations

import base64
import io
from collections.abc import Mapping
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Patch
from matplotlib.ticker import FuncFormatter

from hil.report.data import ErrorSet

BEFORE = "#a3acb9"  # grey: the uncalibrated arm
AFTER = "#1f6fb4"  # blue: the calibrated model
REJECTED = "#d62728"
THRESHOLD = "#d62728"
AXES = ("#d62728", "#2ca02c", "#1f77b4")  # x, y, z in the usual RGB order
DPI = 144
WIDTH = 9.0  # inches; the HTML scales images to the page width


def _figure(height: float, **kw: object) -> Figure:
    fig = Figure(figsize=(WIDTH, height), dpi=DPI, layout="constrained", **kw)
    FigureCanvasAgg(fig)
    return fig


def _style(ax: Axes) -> None:
    ax.spines[["top", "right"]].set_visible(False)
    ax.tick_params(labelsize=8)
    ax.grid(axis="y", color="#e3e6ea", linewidth=0.6)
    ax.set_axisbelow(True)


def png(fig: Figure) -> bytes:
    """The figure as PNG bytes (white background, so it prints and shows in dark viewers)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, facecolor="white")
    return buf.getvalue()


def data_uri(png_bytes: bytes) -> str:
    """A ``data:`` URI embedding PNG bytes, for a self-contained ``<img src>``."""
    return "data:image/png;base64," + base64.b64encode(png_bytes).decode("ascii")


def pose_axis_label(xlabel: str, lines: np.ndarray | None, line_kind: str = "input line") -> str:
    """The x-axis label of a per-pose plot: a campaign's poses are labelled by their pose numbers
    (``line_kind`` ``"pose"``: the label is left as it is), a file's by their input lines."""
    return xlabel + (f" ({line_kind})" if lines is not None and line_kind != "pose" else "")


def _pose_ticks(ax: Axes, n: int, labels: np.ndarray | None = None) -> None:
    """At most ~25 pose labels: 1-based pose numbers, or the poses' own labels (input file lines or
    campaign pose numbers) when known."""
    step = max(1, int(np.ceil(n / 25)))
    ticks = np.arange(0, n, step)
    ax.set_xticks(ticks)
    ax.set_xticklabels([str(int(labels[i])) if labels is not None else str(i + 1) for i in ticks])
    ax.set_xlim(-0.7, n - 0.3)


def errors_per_pose(before: ErrorSet | None, after: ErrorSet, *, accept_rms: float | None = None,
                    rejected: np.ndarray | None = None, lines: np.ndarray | None = None,
                    xlabel: str = "validation pose", line_kind: str = "input line") -> bytes:
    """Grouped bars of each pose's error before and after calibration, on a log axis (mm).

    Dashed lines mark each RMS, a red line the acceptance threshold (on the RMS); poses the fit
    rejected as outliers (`rejected`, a bool mask) are drawn in red and left out of the "after"
    RMS, which is then the fit RMS.
    """
    n = len(after.norms)
    fig = _figure(3.1)
    ax = fig.add_subplot()
    _style(ax)
    x = np.arange(n)
    both = before is not None and len(before.norms) == n
    w = 0.4 if both else 0.7
    handles = []
    if both:
        ax.bar(x - w / 2, before.norms * 1e3, w, color=BEFORE, label="before")
        ax.axhline(before.rms * 1e3, color="#6b7684", ls="--", lw=1)
        handles.append(Patch(color=BEFORE, label=f"before calibration (RMS {before.rms * 1e3:.3f} mm)"))
    colors = np.full(n, AFTER, dtype=object)
    if rejected is not None and np.any(rejected):
        colors[np.asarray(rejected, dtype=bool)] = REJECTED
    ax.bar(x + (w / 2 if both else 0), after.norms * 1e3, w, color=list(colors))
    kept = after.norms if rejected is None else after.norms[~np.asarray(rejected, dtype=bool)]
    rms_after = float(np.sqrt(np.mean(kept**2))) if kept.size else float("nan")
    ax.axhline(rms_after * 1e3, color=AFTER, ls="--", lw=1)
    used = " over used poses" if rejected is not None and np.any(rejected) else ""
    handles.append(Patch(color=AFTER, label=f"after calibration (RMS {rms_after * 1e3:.3f} mm{used})"))
    if rejected is not None and np.any(rejected):
        handles.append(Patch(color=REJECTED, label="rejected outlier"))
    if accept_rms is not None:
        ax.axhline(accept_rms * 1e3, color=THRESHOLD, ls=":", lw=1.4)
        handles.append(Patch(color=THRESHOLD, label=f"acceptance RMS {accept_rms * 1e3:.3f} mm"))
    values = np.r_[after.norms, before.norms if both else []] * 1e3
    positive = values[values > 0]
    if positive.size:
        ax.set_yscale("log")
        lo = positive.min() / 2
        hi = max(positive.max(), (accept_rms or 0) * 1e3) * 2
        ax.set_ylim(lo, hi)
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.set_ylabel("3-D error (mm, log scale)", fontsize=9)
    ax.set_xlabel(pose_axis_label(xlabel, lines, line_kind), fontsize=9)
    _pose_ticks(ax, n, lines)
    ax.legend(handles=handles, fontsize=8, ncols=len(handles), loc="lower center",
              bbox_to_anchor=(0.5, 1.0), frameon=False)
    return png(fig)


def histograms(before: ErrorSet | None, after: ErrorSet, *, accept_rms: float | None = None) -> bytes:
    """Histograms of the validation errors before and after calibration, one panel each (mm)."""
    sets = [("before calibration", before, BEFORE), ("after calibration", after, AFTER)]
    sets = [s for s in sets if s[1] is not None and s[1].per_pose]
    fig = _figure(2.6)
    axes = fig.subplots(1, len(sets), squeeze=False)[0]
    for ax, (title, errors, color) in zip(axes, sets, strict=True):
        _style(ax)
        e = errors.norms * 1e3
        bins = int(np.clip(np.sqrt(len(e)) * 1.5, 5, 30))
        ax.hist(e, bins=bins, color=color, edgecolor="white", linewidth=0.5)
        ax.axvline(errors.rms * 1e3, color="#333", ls="--", lw=1)
        if accept_rms is not None and title.startswith("after"):
            ax.axvline(accept_rms * 1e3, color=THRESHOLD, ls=":", lw=1.4)
        ax.set_title(f"{title}: {len(e)} poses, RMS {errors.rms * 1e3:.3f} mm (dashed)", fontsize=9)
        ax.set_xlabel("3-D error (mm)", fontsize=9)
        ax.set_ylabel("poses", fontsize=9)
        ax.set_xlim(left=0)
    return png(fig)


def per_axis(vectors: np.ndarray, *, xlabel: str = "validation pose",
             lines: np.ndarray | None = None, line_kind: str = "input line") -> bytes:
    """Signed x, y, z errors (mm) of each pose after calibration, and their spread per axis."""
    v = np.asarray(vectors, dtype=float).reshape(-1, 3) * 1e3
    n = len(v)
    fig = _figure(2.9)
    left, right = fig.subplots(1, 2, width_ratios=[5, 1], sharey=True)
    _style(left)
    _style(right)
    x = np.arange(n)
    w = 0.27
    for k, (name, color) in enumerate(zip("xyz", AXES, strict=True)):
        left.bar(x + (k - 1) * w, v[:, k], w, color=color, label=name)
    left.axhline(0, color="#555", lw=0.6)
    left.set_ylabel("error (mm)", fontsize=9)
    left.set_xlabel(pose_axis_label(xlabel, lines, line_kind), fontsize=9)
    _pose_ticks(left, n, lines)
    left.legend(fontsize=8, ncols=3, loc="lower center", bbox_to_anchor=(0.5, 1.0), frameon=False)
    box = right.boxplot([v[:, 0], v[:, 1], v[:, 2]], tick_labels=["x", "y", "z"], widths=0.6,
                        patch_artist=True, medianprops={"color": "black"})
    for patch, color in zip(box["boxes"], AXES, strict=True):
        patch.set_facecolor(color)
        patch.set_alpha(0.55)
    right.set_title("spread", fontsize=9)
    return png(fig)


WARMUP_COLOR = "#ff7f0e"  # orange: the arm warming up
DRIFT_COLOR = AFTER  # blue: the drift watch while measuring


def _run_offsets(series: list[Mapping[str, Any]]) -> dict[int, float]:
    """Each run's start on one time axis (s): a resumed run starts where the previous one's last
    reference measurement was, plus a minute's gap (each run's station clock starts at zero)."""
    offsets: dict[int, float] = {}
    end = 0.0
    for run in sorted({int(s["run"]) for s in series}):
        offsets[run] = end + (60.0 if offsets else 0.0)
        end = offsets[run] + max(float(s["elapsed"]) for s in series if int(s["run"]) == run)
    return offsets


def drift_plot(drift: Mapping[str, Any]) -> bytes:
    """The reference's displacement from its baseline (µm) against station time (min): warm-up
    measurements in orange, the drift watch's in blue, the baseline as a star, the drift limit as a red
    line; a resumed run's series follows the previous one's after a dotted line. With joint temperatures
    reported, a lower panel shows them (°C)."""
    series = [s for s in drift.get("series") or [] if s.get("drift") is not None]
    temps = [s for s in series if s.get("temperatures")]
    fig = _figure(3.6 if temps else 2.9)
    if temps:
        ax, tax = fig.subplots(2, 1, sharex=True, height_ratios=[3, 1])
    else:
        ax, tax = fig.add_subplot(), None
    _style(ax)
    offsets = _run_offsets(series) if series else {}
    minutes = np.array([(offsets[int(s["run"])] + float(s["elapsed"])) / 60.0 for s in series])
    y = np.array([float(s["drift"]) * 1e6 for s in series])
    phase = np.array([str(s.get("phase")) for s in series])
    runs = np.array([int(s["run"]) for s in series])
    handles: list[Any] = []
    for name, color, label in (("warmup", WARMUP_COLOR, "warm-up"), ("drift", DRIFT_COLOR, "drift watch")):
        drawn = None
        for run in sorted(set(runs.tolist())):  # one line per run: a resume is a break, not a slope
            mask = (phase == name) & (runs == run)
            if np.any(mask):
                drawn = ax.plot(minutes[mask], y[mask], "o-", color=color, ms=4, lw=1, label=label)
        handles += drawn or []
    base = [i for i, s in enumerate(series) if s.get("baseline")]
    if base:
        handles += ax.plot(minutes[base], y[base], "*", color="black", ms=11, clip_on=False, zorder=3,
                           label="baseline")
    limit = drift.get("limit")
    top = float(np.max(y)) if len(y) else 0.0
    if isinstance(limit, int | float) and not isinstance(limit, bool):
        handles.append(ax.axhline(float(limit) * 1e6, color=THRESHOLD, ls=":", lw=1.4,
                                  label=f"drift limit {float(limit) * 1e6:g} µm"))
        top = max(top, float(limit) * 1e6)
    for run, start in offsets.items():
        if run != min(offsets):
            ax.axvline(start / 60.0, color="#6b7684", ls=":", lw=1)
            if tax is not None:
                tax.axvline(start / 60.0, color="#6b7684", ls=":", lw=1)
    ax.set_ylim(-0.04 * top if top > 0 else -1.0, 1.08 * top if top > 0 else 1.0)
    ax.set_ylabel("from baseline (µm)", fontsize=9)
    ax.legend(handles=handles, fontsize=8, ncols=len(handles) or 1, loc="lower center",
              bbox_to_anchor=(0.5, 1.0), frameon=False)
    if tax is not None:
        _style(tax)
        tm = np.array([(offsets[int(s["run"])] + float(s["elapsed"])) / 60.0 for s in temps])
        tv = np.array([np.asarray(s["temperatures"], dtype=float) for s in temps])
        trun = np.array([int(s["run"]) for s in temps])
        same = np.allclose(tv, tv[:, :1])  # one temperature for every joint: one line
        colors = [f"C{j}" for j in range(tv.shape[1])]
        for k, run in enumerate(sorted(set(trun.tolist()))):
            m = trun == run
            for j in range(1 if same else tv.shape[1]):
                name = f"joints 1–{tv.shape[1]}" if same else f"joint {j + 1}"
                tax.plot(tm[m], tv[m, j], lw=0.9, color=colors[j], label=name if k == 0 else None)
        tax.set_ylabel("joints (°C)", fontsize=9)
        tax.legend(fontsize=7, ncols=6, loc="upper left", frameon=False)
        tax.set_xlabel("station time (min)", fontsize=9)
    else:
        ax.set_xlabel("station time (min)", fontsize=9)
    return png(fig)
