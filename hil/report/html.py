"""The building blocks of hil's HTML pages: escaping, number formats, tables, figures, the stylesheet.

Shared by the calibration report (`hil.report.render`), the pose test's pages and sections
(`hil.report.pose_test`, `hil.report.verification`) and the fleet report (`hil.report.fleet`), so
that every page looks alike and none of them imports another's page to get them (the calibration
report shows the pose test's section, and the pose test's page uses the same blocks). See
`hil.report.render` for what a page must be: self-contained, escaped, well-formed XML, printable.
"""

from __future__ import annotations

import html
import math
from collections.abc import Iterable, Sequence
from typing import Any

from hil.report.plots import data_uri


def esc(value: Any) -> str:
    """HTML-escaped text of any value (quotes too, so it is safe in attributes)."""
    return html.escape(str(value), quote=True)


def finite(v: float | None) -> bool:
    """A number that can be shown (not None, NaN or infinite)."""
    return v is not None and isinstance(v, int | float) and math.isfinite(v)


def fmt_mm(v: float | None, digits: int = 3) -> str:
    """Metres as millimetres (µm resolution by default); an em dash when unknown. A value that rounds
    to zero is 0.000, never -0.000 (a signed AP component of a few tenths of a µm)."""
    return f"{round(v * 1e3, digits) + 0.0:.{digits}f} mm" if finite(v) else "—"


def fmt_num(v: float | None, spec: str = ".4g") -> str:
    """A number formatted with `spec`; an em dash when unknown."""
    return format(v, spec) if finite(v) else "—"


def table(head: Sequence[str], rows: Iterable[Sequence[str]], cls: str = "") -> str:
    """A table from already-escaped cell HTML."""
    th = "".join(f"<th>{h}</th>" for h in head)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" for row in rows)
    attr = f' class="{cls}"' if cls else ""
    return f"<table{attr}><thead><tr>{th}</tr></thead><tbody>{body}</tbody></table>"


def kv(rows: Iterable[tuple[str, str]]) -> str:
    """A two-column key/value table (both cells already escaped)."""
    body = "".join(f"<tr><th>{k}</th><td>{v}</td></tr>" for k, v in rows)
    return f'<table class="kv"><tbody>{body}</tbody></table>'


def figure(png_bytes: bytes, alt: str, caption: str) -> str:
    """A PNG embedded as a ``data:`` URI, with its alternative text and caption."""
    return (f'<figure><img src="{data_uri(png_bytes)}" alt="{esc(alt)}" />'
            f"<figcaption>{esc(caption)}</figcaption></figure>")


def section(ident: str, title: str, body: str) -> str:
    """A report section: its anchor, its title (escaped), its body (already HTML)."""
    return f'<section id="{ident}"><h2>{esc(title)}</h2>{body}</section>'


#: The stylesheet every page inlines (screen and A4 print).
CSS = """
:root { --ok: #1a7f37; --bad: #c62828; --muted: #5f6b7a; --line: #d8dde3; }
* { box-sizing: border-box; }
body { font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif;
  color: #1d2430; margin: 0 auto; max-width: 1000px; padding: 24px; }
header { display: flex; gap: 24px; align-items: stretch; justify-content: space-between;
  border-bottom: 2px solid #1d2430; padding-bottom: 12px; }
h1 { font-size: 24px; margin: 0 0 4px; }
h2 { font-size: 18px; border-bottom: 1px solid var(--line); padding-bottom: 4px; margin-top: 28px; }
h3 { font-size: 15px; margin: 18px 0 6px; }
.sub, .generated, .muted, figcaption, .note { color: var(--muted); }
.sub { margin: 2px 0; }
.generated { font-size: 12px; margin: 6px 0 0; }
.verdict { min-width: 260px; text-align: center; color: white; border-radius: 8px; padding: 10px 16px; }
.verdict .big { font-size: 44px; font-weight: 800; letter-spacing: 0.08em; line-height: 1.1; }
.verdict.pass { background: var(--ok); }
.verdict.fail { background: var(--bad); }
.tiles { display: grid; grid-template-columns: repeat(auto-fill, minmax(220px, 1fr)); gap: 10px;
  margin-top: 16px; }
.tile { border: 1px solid var(--line); border-radius: 6px; padding: 8px 12px; }
.tile .label { font-size: 12px; text-transform: uppercase; letter-spacing: 0.04em; color: var(--muted); }
.tile .value { font-size: 17px; margin: 2px 0; }
.tile .note { font-size: 12px; }
table { border-collapse: collapse; margin: 6px 0 12px; font-size: 13px; }
th, td { border-bottom: 1px solid var(--line); padding: 3px 10px 3px 0; text-align: left;
  vertical-align: top; }
thead th { border-bottom: 2px solid #9aa4b1; }
table.num td { font-variant-numeric: tabular-nums; }
table.num td + td { text-align: right; }
table.kv th { font-weight: 600; padding-right: 24px; }
code { font-size: 12px; word-break: break-all; }
figure { margin: 12px 0 18px; }
figure img { width: 100%; height: auto; display: block; }
figcaption { font-size: 12px; margin-top: 2px; }
.meter { display: inline-block; width: 160px; height: 10px; background: #e8ebef; vertical-align: middle;
  margin-left: 8px; border-radius: 2px; }
.meter span { display: block; height: 100%; background: var(--ok); border-radius: 2px; }
.stack { display: flex; height: 16px; max-width: 600px; border-radius: 3px; overflow: hidden; }
.stack span { display: block; height: 100%; }
.swatch { display: inline-block; width: 10px; height: 10px; margin-right: 6px; }
* { -webkit-print-color-adjust: exact; print-color-adjust: exact; }
@page { size: A4; margin: 14mm; }
@media print {
  body { padding: 0; max-width: none; font-size: 11px; }
  figure, table, .tile, header { break-inside: avoid; }
  h2, h3 { break-after: avoid; }
}
"""
