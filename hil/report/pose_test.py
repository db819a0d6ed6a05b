"""The ISO 9283 pose test's figures as HTML: AP and RP per pose and mode, the attained positions.

Rendered from the ``hil-verification/1`` document alone, for the pose test's own page
(`hil.report.verification`: ``hil verify --report``, ``hil report`` of its result) and for the
section of the calibration report of ``hil calibrate --verify`` (`calibration_section`,
`hil.report.render`): one rendering, so the two show the same tables and figure. What a saved
document must hold to be shown is checked by `hil.report.data.check_verification`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from hil.report.html import esc, figure, fmt_mm, kv, table
from hil.report.plots import _figure as _new_figure
from hil.report.plots import _style, png

#: Colours of the two modes, as the calibration report's before (grey) and after (blue).
MODE_COLOURS = {"uncompensated": "#8a94a3", "compensated": "#1f6fb4"}
MODE_MEANS = {
    "uncompensated": "the controller's own model (its IK of each pose, as movel would drive)",
    "compensated": "hil's calibrated model (each pose solved with it, sent as joints)",
}


def attained_positions(doc: Mapping[str, Any]) -> bytes:
    """Per pose (columns) and mode (rows: x–y, then x–z), the attained positions' offsets from the
    commanded one (base axes; a red cross) and their barycentre (a ring). Each row has its own scale
    (µm when the whole row spans less than 0.1 mm), so the compensated cloud, micrometres from its
    target, is as readable as the uncompensated one millimetres away."""
    from hil.verify.cube import POSE_NAMES

    results = doc["results"]
    rows = [(mode, i, j, label) for mode in results for i, j, label in ((0, 1, "y"), (0, 2, "z"))]
    fig = _new_figure(1.75 * len(rows) + 0.4)
    axes = fig.subplots(len(rows), len(POSE_NAMES), squeeze=False)
    for r, (mode, i, j, label) in enumerate(rows):
        offsets = {p["pose"]: np.asarray(p["offsets"], float)
                   for p in results[mode]["poses"] if "offsets" in p}
        span = max((float(np.max(np.abs(d))) for d in offsets.values()), default=0.0)
        scale, unit = (1e6, "µm") if span < 1e-4 else (1e3, "mm")
        colour = MODE_COLOURS.get(mode, "#444")
        for col, name in enumerate(POSE_NAMES):
            ax = axes[r][col]
            _style(ax)
            ax.grid(axis="x", color="#e3e6ea", linewidth=0.6)
            ax.axhline(0, color="#bbb", linewidth=0.5)
            ax.axvline(0, color="#bbb", linewidth=0.5)
            if name in offsets:
                d = offsets[name] * scale
                ax.scatter(d[:, i], d[:, j], s=8, color=colour, alpha=0.75, linewidths=0)
                ax.scatter([d[:, i].mean()], [d[:, j].mean()], s=70, facecolors="none", edgecolors=colour,
                           linewidths=1.3)
            ax.plot([0], [0], marker="+", color="#d62728", markersize=11, mew=1.6)
            _square(ax, offsets[name][:, [i, j]] * scale if name in offsets else np.zeros((0, 2)))
            ax.tick_params(labelsize=7)
            ax.set_xlabel(f"x ({unit})", fontsize=7)
            if col == 0:
                ax.set_ylabel(f"{mode}\n{label} ({unit})", fontsize=8)
            if r == 0:
                ax.set_title(name, fontsize=9)
    return png(fig)


def _square(ax: Any, points: np.ndarray) -> None:
    """Equal scales on a square panel holding the points and the cross with room around them: left to
    matplotlib, a cloud millimetres off its cross sits on the panel's edge, ring and points cut."""
    both = np.vstack([points, np.zeros((1, 2))])
    lo, hi = both.min(axis=0), both.max(axis=0)
    centre, half = (lo + hi) / 2, 0.65 * float(np.max(hi - lo))
    half = half if half > 0 else 1.0
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_aspect("equal", adjustable="box")


def _rows(block: Mapping[str, Any]) -> list[list[str]]:
    rows = []
    for p in block["poses"]:
        if "AP_P" not in p:
            rows.append([esc(p["pose"]), esc(p.get("n", 0))] + ["—"] * 6)
            continue
        rows.append([esc(p["pose"]), esc(p["n"])] + [esc(fmt_mm(p[k])) for k in
                                                     ("AP_x", "AP_y", "AP_z", "AP_P", "S_l", "RP_l")])
    return rows


def results_body(doc: Mapping[str, Any]) -> str:
    """AP and RP per pose, one table per mode (and the uncompensated poses in the controller's own
    frame, when judged there too), then the figure of the attained positions."""
    head = ["pose", "n", "AP_x", "AP_y", "AP_z", "AP_P", "S_l", "RP_l"]
    parts = []
    for mode, block in doc["results"].items():
        parts.append(f"<h3>{esc(mode)}: {esc(MODE_MEANS.get(mode, ''))}</h3>"
                     + table(head, _rows(block), "num"))
    own = doc.get("own_frame")
    if own:
        # the registered frame's note is worded for a test without a model ("no model: ..."); here
        # there is one, and the frame is fitted to the uncompensated points alone
        note = str(own["frame"].get("note", "")).removeprefix("no model: ")
        parts.append("<h3>uncompensated, in the controller's own frame</h3>"
                     f'<p class="muted">{esc(note[:1].upper() + note[1:])}. The tables above use the '
                     "model's frame; the difference is the two models' base frames, not the arm.</p>"
                     + table(head, _rows(own), "num"))
    parts.append(figure(attained_positions(doc), "attained positions around the commanded one per pose",
                        "Attained positions of each pose relative to the commanded one (red cross), "
                        "in the robot base frame's axes (mm; µm in a row spanning less than 0.1 mm); "
                        "rings: barycentres. AP is the ring's distance from the cross, RP the cloud's "
                        "size (l̄ + 3·S_l)."))
    parts.append(f'<p class="muted">Orientation: {esc(doc.get("orientation", ""))}. '
                 f"AP components are along the robot base frame's axes.</p>")
    return "".join(parts)


def setup_table(doc: Mapping[str, Any]) -> str:
    """How the test was made: standard, cube, cycle, tool, frame, model, the poses, skipped visits."""
    cube, frame, tool = doc.get("cube", {}), doc.get("frame", {}), doc.get("tool", {})
    poses = doc.get("poses", {})
    rows = [("standard", esc(doc.get("standard", ""))),
            ("cube", esc(f"centre {_vec(cube.get('centre'))} m, edge {fmt_mm(cube.get('edge'))}, "
                         f"measuring plane {cube.get('plane', '')}")),
            ("cycle", esc(", ".join(doc.get("cycle_order", [])) + f" × {doc.get('cycles')}")),
            ("tool", esc(f"SMR at {_vec(tool.get('smr'))} m in the flange frame; facing the tracker at "
                         f"{_vec((tool.get('faces') or {}).get('tracker'))} m "
                         f"(from the {(tool.get('faces') or {}).get('from', '—')})")),
            ("frame", esc(frame.get("note", "—"))),
            ("model", esc((doc.get("model") or {}).get("source", "none: uncompensated only"))),
            ("model sha256", esc((doc.get("model") or {}).get("sha256", "—")))]
    rows += [(esc(name), esc(f"{_vec(p)} m")) for name, p in poses.items()]
    skipped = doc.get("skipped") or []
    if skipped:
        rows.append(("skipped visits", esc("; ".join(f"{s['index']} ({s['pose']} {s['mode']}): {s['reason']}"
                                                     for s in skipped))))
    return kv(rows)


def _vec(values: Sequence[float] | None) -> str:
    if values is None:
        return "—"
    return "[" + ", ".join(f"{float(v):.4f}" for v in values) + "]"


def calibration_section(doc: Mapping[str, Any]) -> str:
    """The body of the calibration report's pose-test section (``hil calibrate --verify``): the same
    tables, figure and test setup as the pose test's own page, from the ``verification`` block of the
    calibration's result — or why there are none (the test was not run, or did not finish)."""
    if "results" not in doc:
        status = doc.get("status", "—")
        why = doc.get("reason") or doc.get("error")
        text = (f"The pose test was not run: {why}." if status == "not run" else
                f"The pose test did not finish (status {status}{f': {why}' if why else ''}); hil verify "
                f"with this result as --model continues it (campaign {doc.get('campaign', '—')}).")
        return f'<p class="muted">{esc(text)}</p>'
    campaign = doc.get("campaign")
    run = f"verification campaign {campaign}" if campaign else "a verification"
    return (f'<p class="muted">{esc(doc.get("standard", ""))}. Run right after the calibration with the '
            f"model it produced, as {esc(run)}: {esc(doc.get('measured', '—'))} of "
            f"{esc(doc.get('visits', '—'))} visits measured. The worst poses' AP and RP are in the "
            "summary above.</p>"
            + results_body(doc) + "<h3>Test</h3>" + setup_table(doc))


