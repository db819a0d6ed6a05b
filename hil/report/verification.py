"""The report of an ISO 9283 pose test (``hil verify --report``), one self-contained HTML file.

Built from the ``hil-verification/1`` document alone (so a saved result renders the same report years
later), with the calibration report's page style and conventions (`hil.report.render`): a table of AP
and RP per pose for both modes, and a figure of the attained positions around the commanded one per
pose — the standard's picture of accuracy (the cloud's offset) and repeatability (its size).
"""

from __future__ import annotations

import datetime as _dt
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from hil import __version__
from hil.files.outputs import atomic_write_text
from hil.report.plots import _figure as _new_figure
from hil.report.plots import _style, png
from hil.report.render import CSS, _figure, _kv, _section, _table, esc, fmt_mm

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
            ax.set_aspect("equal", adjustable="datalim")
            ax.tick_params(labelsize=7)
            ax.set_xlabel(f"x ({unit})", fontsize=7)
            if col == 0:
                ax.set_ylabel(f"{mode}\n{label} ({unit})", fontsize=8)
            if r == 0:
                ax.set_title(name, fontsize=9)
    return png(fig)


def _rows(block: Mapping[str, Any]) -> list[list[str]]:
    rows = []
    for p in block["poses"]:
        if "AP_P" not in p:
            rows.append([esc(p["pose"]), esc(p.get("n", 0))] + ["—"] * 6)
            continue
        rows.append([esc(p["pose"]), esc(p["n"])] + [esc(fmt_mm(p[k])) for k in
                                                     ("AP_x", "AP_y", "AP_z", "AP_P", "S_l", "RP_l")])
    return rows


def _summary(doc: Mapping[str, Any]) -> str:
    tiles = []
    for mode, block in doc.get("results", {}).items():
        tiles.append((f"AP {mode}", f"<b>{esc(fmt_mm(block['AP_max']))}</b>", "worst pose, AP_P"))
        tiles.append((f"RP {mode}", f"<b>{esc(fmt_mm(block['RP_max']))}</b>", "worst pose, RP_l"))
    tiles.append(("Cycles", f"<b>{esc(doc.get('cycles'))}</b>",
                  f"{esc(doc.get('measured', '—'))} of {esc(doc.get('visits', '—'))} visits measured"))
    cells = "".join(f'<div class="tile"><div class="label">{esc(label)}</div><div class="value">{value}</div>'
                    f'<div class="note">{esc(note)}</div></div>' for label, value, note in tiles)
    return f'<div class="tiles">{cells}</div>'


def _results(doc: Mapping[str, Any]) -> str:
    head = ["pose", "n", "AP_x", "AP_y", "AP_z", "AP_P", "S_l", "RP_l"]
    parts = []
    for mode, block in doc["results"].items():
        parts.append(f"<h3>{esc(mode)}: {esc(MODE_MEANS.get(mode, ''))}</h3>"
                     + _table(head, _rows(block), "num"))
    own = doc.get("own_frame")
    if own:
        parts.append("<h3>uncompensated, in the controller's own frame</h3>"
                     f'<p class="muted">{esc(own["frame"]["note"])}. The tables above use the model\'s '
                     "frame; the difference is the two models' base frames, not the arm.</p>"
                     + _table(head, _rows(own), "num"))
    parts.append(_figure(attained_positions(doc), "attained positions around the commanded one per pose",
                         "Attained positions of each pose relative to the commanded one (red cross), "
                         "in the robot base frame's axes, mm; rings: barycentres. AP is the ring's "
                         "distance from the cross, RP the cloud's size (l̄ + 3·S_l)."))
    parts.append(f'<p class="muted">Orientation: {esc(doc.get("orientation", ""))}. '
                 f"AP components are along the robot base frame's axes.</p>")
    return "".join(parts)


def _setup(doc: Mapping[str, Any]) -> str:
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
    return _kv(rows)


def _controller_section(doc: Mapping[str, Any]) -> str:
    block = doc.get("controller") or {}
    if not block.get("reported"):
        return f'<p class="muted">{esc(block.get("note", "not reported"))}</p>'
    from hil.report.render import _controller

    table = _controller(block, str(doc.get("robot", "")))
    return table.replace("Its error on the held-out poses is in the validation table above.",
                         "Its accuracy is the uncompensated test's.")


def _vec(values: Sequence[float] | None) -> str:
    if values is None:
        return "—"
    return "[" + ", ".join(f"{float(v):.4f}" for v in values) + "]"


def render_verification(doc: Mapping[str, Any], *, generated: str | None = None) -> str:
    """The whole report of a finished verification as one self-contained HTML (well-formed XML)."""
    if generated is None:
        generated = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    robot = doc.get("robot_info") or {}
    who = " ".join(x for x in (str(robot.get("model") or doc.get("robot", "")).upper(),
                               robot.get("serial") and f"serial {robot['serial']}") if x)
    title = f"ISO 9283 pose test {who} {doc.get('campaign', '')}".strip()
    sections = [
        _section("results", "Pose accuracy and repeatability", _results(doc)),
        _section("setup", "Test", _setup(doc)),
        _section("controller", "The controller's own model", _controller_section(doc)),
    ]
    header = (f'<header><div class="title"><h1>ISO 9283 pose test</h1>'
              f'<p class="sub">{esc(who)} · station {esc(doc.get("station", "—"))} · campaign '
              f'{esc(doc.get("campaign", "—"))}</p></div></header>'
              f'<p class="generated">Generated {esc(generated)} by hil {esc(__version__)}.</p>')
    return ("<!DOCTYPE html>\n"
            '<html lang="en"><head><meta charset="utf-8" />'
            '<meta name="viewport" content="width=device-width, initial-scale=1" />'
            f"<title>{esc(title)}</title><style>{CSS}</style></head>\n<body>"
            + header + _summary(doc) + "\n".join(sections) + "</body></html>\n")


def write_verification_report(doc: Mapping[str, Any], path: str | os.PathLike[str], *,
                              generated: str | None = None) -> Path:
    """Render the report and write it atomically; returns the path."""
    atomic_write_text(path, render_verification(doc, generated=generated))
    return Path(path)
