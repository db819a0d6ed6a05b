"""Plots drawn with braille dots, so they work in any UTF-8 terminal over SSH (no graphics protocol).

A braille character holds 2 × 4 dots, and a terminal cell is about twice as tall as it is wide, so
the dots are nearly square: one scale for both axes keeps top and side views undistorted.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from rich.text import Text
from textual.widget import Widget

# dot (column, row) -> bit of the braille character U+2800 + bits
_BITS = ((0x01, 0x02, 0x04, 0x40), (0x08, 0x10, 0x20, 0x80))


@dataclass
class Series:
    """Points to draw: as braille dots (`marker` None) or as one character per point."""

    x: np.ndarray
    y: np.ndarray
    style: str = ""
    marker: str | None = None
    line: bool = False  # join consecutive points


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
        n = max(abs(x1 - x0), abs(y1 - y0), 1)
        for k in range(n + 1):
            self.dot(round(x0 + (x1 - x0) * k / n), round(y0 + (y1 - y0) * k / n), style)

    def char(self, col: int, row: int, ch: str, style: str = "") -> None:
        if 0 <= col < self.width and 0 <= row < self.height:
            self.chars[(col, row)] = (ch, style)

    def text(self, col: int, row: int, s: str, style: str = "") -> None:
        for k, ch in enumerate(s):
            self.char(col + k, row, ch, style)

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


def _fmt(v: float) -> str:
    return f"{v:.2g}" if abs(v) < 10 else f"{v:.0f}"


class PlotView(Widget):
    """A titled scatter or line plot of a few series, scaled to fit the widget.

    `equal` keeps one scale on both axes (for geometry); otherwise each axis is stretched to fill
    (for a time series). The y range always includes `y_floor` when it is given (0 for errors).
    """

    DEFAULT_CSS = "PlotView { height: 1fr; }"

    def __init__(self, title: str = "", *, equal: bool = False, y_floor: float | None = None,
                 id: str | None = None, classes: str | None = None) -> None:
        super().__init__(id=id, classes=classes)
        self.title = title
        self.equal = equal
        self.y_floor = y_floor
        self.series: list[Series] = []
        self.empty_text = "no data yet"

    def plot(self, series: Sequence[Series], title: str | None = None) -> None:
        self.series = list(series)
        if title is not None:
            self.title = title
        self.refresh()

    def render(self) -> Text:
        width, height = self.content_size.width, self.content_size.height
        canvas = BrailleCanvas(width, height)
        canvas.text(0, 0, self.title[:width], "bold")
        data = [s for s in self.series if len(s.x)]
        if not data or height < 3 or width < 8:
            if height > 1:
                canvas.text(0, 1, self.empty_text[:width], "dim")
            return canvas.render()
        xs = np.concatenate([s.x for s in data])
        ys = np.concatenate([s.y for s in data])
        if self.y_floor is not None:
            ys = np.append(ys, self.y_floor)
        x0, x1, y0, y1 = float(xs.min()), float(xs.max()), float(ys.min()), float(ys.max())
        pw, ph = 2 * width - 2, 4 * (height - 1) - 2  # dots, one title row, a small margin
        sx = (x1 - x0) / pw if x1 > x0 else 1.0
        sy = (y1 - y0) / ph if y1 > y0 else 1.0
        if self.equal:
            sx = sy = max(sx, sy, 1e-9)
            x0 -= (pw * sx - (x1 - x0)) / 2  # centre the data
            y0 -= (ph * sy - (y1 - y0)) / 2
            y1 = y0 + ph * sy
        top = 4  # first dot row below the title

        def to_dots(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            px = np.rint((x - x0) / sx).astype(int) + 1
            py = top + ph - np.rint((y - y0) / sy).astype(int)
            return px, py

        for s in data:
            px, py = to_dots(np.asarray(s.x, float), np.asarray(s.y, float))
            if s.marker is None:
                for k in range(len(px)):
                    canvas.dot(int(px[k]), int(py[k]), s.style)
                    if s.line and k:
                        canvas.line(int(px[k - 1]), int(py[k - 1]), int(px[k]), int(py[k]), s.style)
        for s in data:  # characters over the dots
            if s.marker is not None:
                px, py = to_dots(np.asarray(s.x, float), np.asarray(s.y, float))
                for k in range(len(px)):
                    canvas.char(int(px[k]) // 2, int(py[k]) // 4, s.marker, s.style)
        if not self.equal:  # a time series: say what the top of the plot means
            label = f"max {_fmt(y1)}"
            if len(self.title) + len(label) < width:
                canvas.text(width - len(label), 0, label, "dim")
        return canvas.render()
