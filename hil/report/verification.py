"""The report of an ISO 9283 pose test (``hil verify --report``), one self-contained HTML file.

Built from the ``hil-verification/1`` document alone (so a saved result renders the same report years
later), with the calibration report's page style and conventions (`hil.report.render`): a table of AP
and RP per pose for both modes, and a figure of the attained positions around the commanded one per
pose — the standard's picture of accuracy (the cloud's offset) and repeatability (its size).

The tables and the figure are `hil.report.pose_test`'s, which the calibration report of ``hil
calibrate --verify`` shows too; ``hil report --result`` renders this page from a saved
``hil-verification/1`` (`hil.report.data.check_verification` first refuses, in one line, a result it
could not show).
"""

from __future__ import annotations

import datetime as _dt
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from hil import __version__
from hil.files.outputs import atomic_write_text
from hil.report.html import CSS, esc, fmt_mm
from hil.report.html import section as _section
from hil.report.pose_test import results_body, setup_table


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


def _controller_section(doc: Mapping[str, Any]) -> str:
    block = doc.get("controller") or {}
    if not block.get("reported"):
        return f'<p class="muted">{esc(block.get("note", "not reported"))}</p>'
    from hil.report.render import _controller

    table = _controller(block, str(doc.get("robot", "")))
    return table.replace("Its error on the held-out poses is in the validation table above.",
                         "Its accuracy is the uncompensated test's.")


def _when(doc: Mapping[str, Any]) -> str:
    """When the test ran (its start → end, UTC), as the calibration report's header says it."""
    def iso(t: Any) -> str | None:
        if not isinstance(t, int | float) or isinstance(t, bool):
            return None
        return _dt.datetime.fromtimestamp(float(t), _dt.UTC).isoformat(timespec="seconds")

    return " → ".join(x for x in (iso(doc.get("started")), iso(doc.get("finished"))) if x) or "—"


def render_verification(doc: Mapping[str, Any], *, generated: str | None = None) -> str:
    """The whole report of a finished verification as one self-contained HTML (well-formed XML)."""
    if generated is None:
        generated = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    robot = doc.get("robot_info") or {}
    who = " ".join(x for x in (str(robot.get("model") or doc.get("robot", "")).upper(),
                               robot.get("serial") and f"serial {robot['serial']}") if x)
    title = f"ISO 9283 pose test {who} {doc.get('campaign', '')}".strip()
    sections = [
        _section("results", "Pose accuracy and repeatability", results_body(doc)),
        _section("setup", "Test", setup_table(doc)),
        _section("controller", "The controller's own model", _controller_section(doc)),
    ]
    header = (f'<header><div class="title"><h1>ISO 9283 pose test</h1>'
              f'<p class="sub">{esc(who)} · station {esc(doc.get("station", "—"))} · campaign '
              f'{esc(doc.get("campaign", "—"))}</p><p class="sub">{esc(_when(doc))}</p></div></header>'
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
