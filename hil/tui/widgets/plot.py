"""Plots drawn with braille dots, so they work in any UTF-8 terminal over SSH (no graphics protocol).

A braille character holds 2 × 4 dots, and a terminal cell is about twice as tall as it is wide, so
the dots are nearly square: one scale for both axes keeps top and side views undistorted.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from rich.text import Text
from textual.widget import Widget

# dot (column, row) -> bit of the braille character U+2800 + bits
_BITS = ((0x01, 0x02, 0x04, 0x40), (0x08, 0x10, 0x20, 0x80))


@dataclass(eq=False)  # compared by identity (the arrays have no truth value)
class Series:
    """Points to draw: as braille dots (`marker` None) or as one character per point."""

    x: np.ndarray
    y: np.ndarray
    style: str = ""
    marker: str | None = None
    line: bool = False  # join consecutive points
    label: str = ""  # in the legend (none when empty)
    optional: bool = False  # may lie off the plot rather than shrink the rest (see `PlotView`)


def _segment(x0: int, y0: int, x1: int, y1: int) -> list[tuple[int, int]]:
    """The dots of a straight line, both ends included."""
    n = max(abs(x1 - x0), abs(y1 - y0), 1)
    return [(round(x0 + (x1 - x0) * k / n), round(y0 + (y1 - y0) * k / n)) for k in range(n + 1)]


class BrailleCanvas:
    """A width × height cell grid of braille dots plus per-cell characters drawn over them."""

    def __init__(self, width: int, height: int) -> None:
        self.width, self.height = max(1, width), max(1, height)
        self.bits = np.zeros((self.height, self.width), dtype=np.int32)
        self.dot_style: list[list[str]] = [[""] * self.width for _ in range(self.height)]
        self.chars: dict[tuple[int, int], tuple[str, str]] = {}

    def dot(self, px: int, py: int, style: str = "") -> None:
        """Set the dot at (px, py) in dot coordinates, origin top-left."""
        if 0 <= px < 2 * self.width and 0 <= py < 4 * self.height:
            row, col = py // 4, px // 2
            self.bits[row, col] |= _BITS[px % 2][py % 4]
            self.dot_style[row][col] = style

    def line(self, x0: int, y0: int, x1: int, y1: int, style: str = "") -> None:
        for x, y in _segment(x0, y0, x1, y1):
            self.dot(x, y, style)

    def char(self, col: int, row: int, ch: str, style: str = "") -> None:
        if 0 <= col < self.width and 0 <= row < self.height:
            self.chars[(col, row)] = (ch, style)

    def text(self, col: int, row: int, s: str, style: str = "") -> None:
        for k, ch in enumerate(s):
            self.char(col + k, row, ch, style)

    def rich_text(self, col: int, row: int, text: Text) -> None:
        """`text` (one line, one cell per character) with its styles."""
        styles = [""] * len(text.plain)
        for span in text.spans:
            for k in range(span.start, min(span.end, len(styles))):
                styles[k] = str(span.style)
        for k, ch in enumerate(text.plain):
            self.char(col + k, row, ch, styles[k])

    def render(self) -> Text:
        out = Text()
        for row in range(self.height):
            for col in range(self.width):
                if (col, row) in self.chars:
                    ch, style = self.chars[(col, row)]
                    out.append(ch, style)
                elif self.bits[row, col]:
                    out.append(chr(0x2800 + int(self.bits[row, col])), self.dot_style[row][col])
                else:
                    out.append(" ")
            if row < self.height - 1:
                out.append("\n")
        return out


#: An `optional` series (a tracker metres away) joins the plotted range only if it lies within this
#: many of the other data's spans beyond their edges; farther, it is drawn at the border, pointing off.
NEAR_SPANS = 2.0
_ARROWS = {(-1, 0): "←", (1, 0): "→", (0, -1): "↓", (0, 1): "↑",
           (-1, -1): "↙", (-1, 1): "↖", (1, -1): "↘", (1, 1): "↗"}


def nice_step(span: float, count: int) -> float:
    """The smallest 1, 2 or 5 × 10^k step that cuts `span` into at most `count` intervals."""
    if not span > 0 or not math.isfinite(span):
        return 1.0
    raw = span / max(1, count)
    base = 10.0 ** math.floor(math.log10(raw))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * base >= raw * (1 - 1e-9):
            return m * base
    return 10.0 * base


def ticks(lo: float, hi: float, step: float) -> list[float]:
    """Multiples of `step` in [lo, hi]."""
    first = math.ceil(lo / step - 1e-9)
    last = math.floor(hi / step + 1e-9)
    return [k * step for k in range(first, last + 1)]


def tick_label(v: float, step: float) -> str:
    """`v` with as many decimals as `step` needs (no "-0")."""
    decimals = max(0, -math.floor(math.log10(step) + 1e-9)) if step > 0 else 0
    text = f"{v:.{decimals}f}"
    return text[1:] if text.startswith("-") and float(text) == 0 else text


def legend_key(s: Series) -> str:
    return s.marker or ("─" if s.line else "•")


class PlotView(Widget):
    """A titled scatter or line plot of a few series with a scale on both axes and a legend.

    `equal` keeps one scale on both axes (for geometry); otherwise each axis is stretched to fill
    (for a time series, whose y range always includes `y_floor` when it is given: 0 for errors).
    Labelled series are listed in the title row. A point outside the plotted range (an `optional`
    series far from the rest) is drawn at the border with an arrow and "off plot".
    """

    DEFAULT_CSS = "PlotView { height: 1fr; }"

    def __init__(self, title: str = "", *, equal: bool = False, y_floor: float | None = None,
                 x_label: str = "", y_label: str = "", integer_x: bool = False,
                 id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self.title = title
        self.equal = equal
        self.y_floor = y_floor
        self.x_label = x_label  # at the right end of the x axis
        self.y_label = y_label  # left of the axes' corner
        self.integer_x = integer_x
        self.series: list[Series] = []
        self.empty_text = "no data yet"

    def plot(self, series: Sequence[Series], title: str | None = None) -> None:
        self.series = list(series)
        if title is not None:
            self.title = title
        self.refresh()

    def _legend(self, gap: str = "  ") -> Text:
        out = Text()
        for s in self.series:
            if s.label and len(s.x):
                if out:
                    out.append(gap)
                out.append(legend_key(s), s.style)
                out.append(f" {s.label}", "dim")
        return out

    def _range(self, data: list[Series]) -> tuple[float, float, float, float, list[Series]]:
        """Data range (x0, x1, y0, y1) and the series drawn inside it (the rest point off the plot)."""
        fixed = [s for s in data if not s.optional] or data
        xs = np.concatenate([np.asarray(s.x, float) for s in fixed])
        ys = np.concatenate([np.asarray(s.y, float) for s in fixed])
        x0, x1, y0, y1 = float(xs.min()), float(xs.max()), float(ys.min()), float(ys.max())
        inside = list(fixed)
        for s in data:
            if s in fixed:
                continue
            sx, sy = np.asarray(s.x, float), np.asarray(s.y, float)
            wx, wy = max(x1 - x0, 1e-9) * NEAR_SPANS, max(y1 - y0, 1e-9) * NEAR_SPANS
            if (np.all((sx >= x0 - wx) & (sx <= x1 + wx)) and np.all((sy >= y0 - wy) & (sy <= y1 + wy))):
                inside.append(s)
        xs = np.concatenate([np.asarray(s.x, float) for s in inside])
        ys = np.concatenate([np.asarray(s.y, float) for s in inside])
        if self.y_floor is not None:
            ys = np.append(ys, self.y_floor)
        return float(xs.min()), float(xs.max()), float(ys.min()), float(ys.max()), inside

    def render(self) -> Text:
        width, height = self.content_size.width, self.content_size.height
        canvas = BrailleCanvas(width, height)
        title = self.title[:width]
        canvas.text(0, 0, title, "bold")
        legend = self._legend()
        if len(title) + 2 + legend.cell_len > width:
            legend = self._legend(" ")
        data = [s for s in self.series if len(s.x)]
        if legend and len(title) + 2 + legend.cell_len <= width:
            canvas.rich_text(width - legend.cell_len, 0, legend)
        if not data or height < 4 or width < 12:
            if height > 1:
                canvas.text(0, 1, self.empty_text[:width], "dim")
            return canvas.render()
        x0, x1, y0, y1, inside = self._range(data)
        rows = height - 2  # the title row above, the x axis below
        label_x = self.x_label if len(self.x_label) + 12 <= width else ""
        right = width - len(label_x) - 1 if label_x else width  # the plot's right edge; then the x label
        gutter = 5
        for _ in range(2):  # the y labels' width depends on the range, which depends on the width
            cols = right - gutter
            pw, ph = 2 * cols - 1, 4 * rows - 1  # dot intervals across and down
            ax0, ax1, ay0, ay1 = x0, x1, y0, y1
            ystep = nice_step(ay1 - ay0, max(1, rows // 2))
            if not self.equal:
                if ay1 <= ay0:
                    ay1 = ay0 + 1.0
                ystep = nice_step(ay1 - ay0, max(1, rows // 2))
                ay0, ay1 = math.floor(ay0 / ystep + 1e-9) * ystep, math.ceil(ay1 / ystep - 1e-9) * ystep
                if ax1 <= ax0:
                    ax0, ax1 = ax0 - 0.5, ax1 + 0.5
                sx, sy = (ax1 - ax0) / pw, (ay1 - ay0) / ph
            else:
                s = max((ax1 - ax0) / pw, (ay1 - ay0) / ph, 1e-9) * 1.05  # a small margin
                ax0 -= (pw * s - (ax1 - ax0)) / 2  # centre the data
                ay0 -= (ph * s - (ay1 - ay0)) / 2
                ax1, ay1 = ax0 + pw * s, ay0 + ph * s
                sx = sy = s
                ystep = nice_step(ay1 - ay0, max(1, rows // 2))
            yticks = ticks(ay0, ay1, ystep)
            labels = [tick_label(v, ystep) for v in yticks]
            need = max((len(t) for t in labels), default=1) + 1
            if need == gutter:
                break
            gutter = need
        cols = right - gutter

        def to_dots(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            px = np.rint((x - ax0) / sx).astype(int)
            py = 4 + ph - np.rint((y - ay0) / sy).astype(int)  # dot rows start below the title
            return px + 2 * gutter, py

        # the axes: y labels and ticks in the gutter, the x axis with its labels on the bottom row
        bottom = height - 1
        for row in range(1, bottom):
            canvas.char(gutter - 1, row, "│", "dim")
        for v, label in zip(yticks, labels, strict=True):
            _, py = to_dots(np.array([ax0]), np.array([v]))
            row = int(py[0]) // 4
            if 1 <= row < bottom:
                canvas.text(gutter - 1 - len(label), row, label, "dim")
                canvas.char(gutter - 1, row, "┤", "dim")
        canvas.char(gutter - 1, bottom, "└", "dim")
        if self.y_label:
            canvas.text(max(0, gutter - 1 - len(self.y_label)), bottom, self.y_label[:gutter - 1], "dim")
        canvas.text(gutter, bottom, "─" * (right - gutter), "dim")
        if label_x:
            canvas.text(width - len(label_x), bottom, label_x, "dim")
        taken = [False] * right
        xstep = nice_step(ax1 - ax0, max(1, cols // 6))
        if self.integer_x:
            xstep = max(1.0, xstep)
        for v in ticks(ax0, ax1, xstep):
            label = tick_label(v, xstep)
            px, _ = to_dots(np.array([v]), np.array([ay0]))
            start = min(right - len(label), max(gutter, int(px[0]) // 2 - len(label) // 2))
            span = range(max(0, start - 1), min(right, start + len(label) + 1))
            if any(taken[c] for c in span):
                continue
            canvas.text(start, bottom, label, "dim")
            for c in span:
                taken[c] = True

        def in_plot(px: int, py: int) -> bool:
            return 2 * gutter <= px < 2 * right and 4 <= py < 4 * bottom

        for s in inside:
            if s.marker is not None:
                continue
            px, py = to_dots(np.asarray(s.x, float), np.asarray(s.y, float))
            dots = [(int(px[0]), int(py[0]))]
            for k in range(1, len(px)):
                if s.line:
                    dots += _segment(int(px[k - 1]), int(py[k - 1]), int(px[k]), int(py[k]))
                dots.append((int(px[k]), int(py[k])))
            for x, y in dots:
                if in_plot(x, y):
                    canvas.dot(x, y, s.style)
        for s in data:  # characters over the dots; points off the plot at its border
            if s.marker is None and s in inside:
                continue
            px, py = to_dots(np.asarray(s.x, float), np.asarray(s.y, float))
            for k in range(len(px)):
                col, row = int(px[k]) // 2, int(py[k]) // 4
                dx = -1 if col < gutter else 1 if col >= right else 0
                dy = 1 if row < 1 else -1 if row >= bottom else 0
                marker = s.marker or "•"
                if not (dx or dy):
                    canvas.char(col, row, marker, s.style)
                    continue
                col, row = min(max(col, gutter), right - 1), min(max(row, 1), bottom - 1)
                mark = marker + _ARROWS[(dx, dy)] if dx >= 0 else _ARROWS[(dx, dy)] + marker
                note = "off plot "
                text = note + mark if dx > 0 else mark + " " + note.strip()
                if dx > 0:
                    col = right - len(text)
                elif dx == 0:
                    col = min(col, right - len(text))
                canvas.text(max(gutter, col), row, text, s.style)
        return canvas.render()
