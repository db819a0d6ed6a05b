"""Results: did the calibration pass, by how much did it improve the arm, which parameters moved and
how well they are known; export the model, URDF, ROS kinematics YAML and HTML report.

Shows a campaign record from the store — the one just run, or one opened from History — so what the
operator sees is what was recorded, never a figure only the screen knows.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, ClassVar

from rich.console import Group
from rich.table import Table
from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal
from textual.widgets import DataTable, Footer, Static

from hil.calibration.validation_precision import describe_precision
from hil.store.records import VERIFICATION
from hil.tui.screens.base import HilScreen
from hil.tui.screens.history import status_words
from hil.tui.widgets.nav import NavBar
from hil.tui.words import shorten_middle

#: A pose test's modes as the Results grid names them: whole within the 40-column panel at 80x24
#: (the full words cut to "uncompen…"/"compensa…"); the verdict line above spells them out.
MODE_LABELS = {"uncompensated": "uncomp.", "compensated": "comp."}


def model_cv(doc: Any) -> dict[str, Any] | None:
    """A model's ``cross_validation`` block (`hil.calibration.cross_validation`), or None."""
    block = doc.get("cross_validation") if isinstance(doc, dict) else None
    return block if isinstance(block, dict) else None

def _mm(v: Any) -> str:
    return "-" if v is None or not math.isfinite(float(v)) else f"{float(v) * 1e3:.4f}"


def _precision(result: Any) -> dict[str, Any] | None:
    """The stored result document's ``validation.precision`` block (the validation RMS's standard
    error, `hil.calibration.validation_precision`), if it has one."""
    validation = result.get("validation") if isinstance(result, dict) else None
    block = validation.get("precision") if isinstance(validation, dict) else None
    return block if isinstance(block, dict) else None


def _fitted_by_role(rec: Any) -> str:
    """Where the fitted poses came from, when the bootstrap's are among them: "= 30 + 10 bootstrap"
    from the result's ``poses`` counts (`hil.report.mes`), the same figures the report's "fitted"
    line gives; "" when there was no bootstrap or the counts do not add up to the fit's."""
    counts = rec.result.get("poses") if isinstance(rec.result, dict) else None
    fit = (rec.model.doc.get("fit") or {}) if rec.model is not None else {}
    if not isinstance(counts, dict):
        return ""
    boot = (counts.get("bootstrap") or {}).get("measured")
    cal = (counts.get("calibration") or {}).get("measured")
    if not boot or cal is None or boot + cal != fit.get("poses"):
        return ""
    return f"= {cal} + {boot} bootstrap"


#: The table's columns for a calibration: its model's parameters.
PARAMETER_COLUMNS = ("parameter", "value", "std", "unit")


def pose_columns(modes: list[str]) -> tuple[str, ...]:
    """The table's columns for a verification: each pose's AP and RP in each of its modes (mm)."""
    return ("pose", *(f"{what} {MODE_LABELS.get(m, m)}" for m in modes for what in ("AP", "RP")))


def pose_rows(results: dict[str, Any]) -> list[tuple[str, ...]]:
    """A verification's AP_P and RP_l of every pose (``hil-verification/1``'s ``results.<mode>.poses``)
    in mm, one row a pose, in the order the test names them (P1-P5); "-" where a mode measured it
    fewer than twice (no AP/RP). Empty if the document has no per-pose figures."""
    by_pose: dict[str, dict[str, dict[str, Any]]] = {}
    for mode, r in results.items():
        for row in (r.get("poses") or []) if isinstance(r, dict) else []:
            if isinstance(row, dict) and "pose" in row:
                by_pose.setdefault(str(row["pose"]), {})[str(mode)] = row
    return [(pose, *(_mm(by_pose[pose].get(m, {}).get(key)) for m in results for key in ("AP_P", "RP_l")))
            for pose in by_pose]


def _rule_words(result: Any) -> str:
    """Whose threshold the verdict applied, as the result's ``verdict.rule`` says: " auto" (the
    automatic rule: 2 × the cross-validated RMS or the class bound, `hil.campaign.acceptance`) or
    " set" (the user's ``campaign.acceptance``); nothing for an older result without it."""
    verdict = result.get("verdict") if isinstance(result, dict) else None
    rule = verdict.get("rule") if isinstance(verdict, dict) else None
    return {"auto": " auto", "threshold": " set"}.get(str(rule), "")


def parameter_cells(p: dict[str, Any]) -> tuple[str, str, str, str]:
    """name, value, std, unit: translations in mm, rotations in mrad (`.tx` / `.rx` style names)."""
    name = str(p.get("name", "?"))
    axis = name.rsplit(".", 1)[-1]
    angular = axis.startswith("r")
    scale, unit = (1e3, "mrad") if angular else (1e3, "mm")
    value, std = p.get("value"), p.get("std")
    fmt = "{:+.4f}"
    return (name, fmt.format(value * scale) if value is not None else "-",
            f"{std * scale:.4f}" if std is not None and math.isfinite(std) else "-", unit)


class ResultsScreen(HilScreen):
    """One finished (or unfinished) campaign from the store."""

    name_key = "results"
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("m", "export('model')", "Model"),
        Binding("u", "export('urdf')", "URDF"),
        Binding("y", "export('ros')", "ROS YAML"),
        Binding("h", "export('report')", "HTML report"),
        Binding("x", "export('all')", "All"),
    ]

    def __init__(self) -> None:
        super().__init__()
        self.record: Any = None
        self.written: list[str] = []
        self.export_error = ""

    def compose(self) -> ComposeResult:
        yield NavBar("results")
        yield Static(id="verdict")
        with Horizontal(id="result-top"):
            yield Static(id="stats", classes="panel")
            yield Static(id="fit", classes="panel")
        yield DataTable(id="params", cursor_type="row", zebra_stripes=True)
        yield Static(id="exports")
        yield Footer()

    def on_mount(self) -> None:
        self.query_one("#stats").border_title = "Validation, held-out poses, mm"
        self.query_one("#fit").border_title = "Fit"
        self.refresh_view()

    def _table(self, columns: tuple[str, ...], rows: list[tuple[str, ...]]) -> None:
        """The table below the panels, with these columns (a calibration's parameters or a
        verification's poses); hidden when it has no rows (a header over nothing says nothing)."""
        table: DataTable[str] = self.query_one("#params", DataTable)
        if tuple(str(c.label) for c in table.columns.values()) != columns:
            table.clear(columns=True)
            table.add_columns(*columns)
        else:
            table.clear()
        for row in rows:
            table.add_row(*row)
        table.display = bool(rows)

    def show(self, record: Any) -> None:
        if self.record is None or record.id != self.record.id:
            self.written, self.export_error = [], ""
        self.record = record
        self.refresh_bindings()  # the export keys it offers (`check_action`)
        self.refresh_view()

    def exported(self, paths: list[str], error: str) -> None:
        self.written = list(dict.fromkeys([*self.written, *paths]))
        self.export_error = error
        self.refresh_view()

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """Offer an export key only when there is that to export: a model (model, URDF, ROS YAML, all),
        a finished calibration's result (the HTML report)."""
        if action != "export":
            return True
        rec = self.record
        if rec is None:
            return False
        if parameters and parameters[0] == "report":
            return bool(rec.result) and "model" in rec.result
        return rec.model is not None

    def action_export(self, kind: str) -> None:
        if self.record is None:
            self.hil.notify("no campaign shown: run one, or open one from History (5)", severity="warning")
            return
        kinds = ["model", "urdf", "ros", "report"] if kind == "all" else [kind]
        self.hil.start_export(self.record, kinds)

    def refresh_view(self) -> None:
        if not self.is_mounted:
            return
        self.query_one(NavBar).refresh()
        verdict = self.query_one("#verdict", Static)
        stats, fit = self.query_one("#stats", Static), self.query_one("#fit", Static)
        rec = self.record
        if rec is None:
            verdict.update(Text("no campaign yet: run one (3, g) or open one from History (5)", style="dim"))
            stats.update("")
            fit.update("")
            self._table(PARAMETER_COLUMNS, [])
            self._exports()
            return
        s = rec.summary
        if s.kind == VERIFICATION:
            self._verification(rec)
            return
        self.query_one("#stats").border_title = "Validation, held-out poses, mm"
        self.query_one("#fit").border_title = "Fit"
        accept = ((rec.config or {}).get("campaign") or {}).get("acceptance")
        if isinstance(rec.result, dict) and rec.result.get("accept_rms") is not None:
            accept = rec.result["accept_rms"]  # the threshold the verdict applied (automatic or the user's)
        robot = ((rec.config or {}).get("robot") or {}).get("type")
        if accept is None and isinstance(robot, str):
            from hil.campaign.acceptance import threshold

            accept = threshold(None, robot)  # no threshold set: the robot class's bound
        cv = (model_cv(rec.model.doc) if rec.model is not None else None)
        v = rec.validation
        if v is not None:
            word, style = ("PASS", "bold white on green") if v.passed else ("FAIL", "bold white on red")
        else:
            word, style = s.status.upper(), "bold reverse"
        line = Text.assemble((f" {word} ", style), "  ", (rec.id, "bold"), f"  {s.status}")
        if v is not None and accept is not None:
            line.append(f"  RMS {_mm(v.after.get('rms'))} mm {'≤' if v.passed else '>'} "
                        f"{_mm(accept)} mm{_rule_words(rec.result)}")
        precision = describe_precision(_precision(rec.result))
        if v is not None and precision is not None:
            line.append(f"\n validation RMS {precision}", "dim")
        if cv is not None and cv.get("better_than_nominal") is False:
            line.append("\n NOT BETTER THAN NOMINAL by cross-validation: exports refuse this model",
                        "bold red")
        if rec.detail and v is None:
            line.append(f"\n{rec.detail}", "dim")
        verdict.update(line)
        grid = Table("", "before", "after", box=None, padding=(0, 1), show_edge=False)
        if v is not None:
            for key in ("rms", "max", "mean"):
                grid.add_row(key, _mm(v.before.get(key)), Text(_mm(v.after.get(key)), style="bold"))
            grid.add_row("poses", str(v.before.get("count", "-")), str(v.after.get("count", "-")))
            if cv is not None:  # the same models held out by cross-validation on the fitted poses
                nominal, calibrated = cv.get("nominal") or {}, cv.get("calibrated") or {}
                grid.add_row(f"CV rms ({cv.get('folds')}-fold)", _mm(nominal.get("rms")),
                             Text(_mm(calibrated.get("rms")), style="bold"))
                if isinstance(cv.get("controller"), dict):
                    grid.add_row("CV controller", _mm(cv["controller"].get("rms")), "")
        else:
            grid.add_row("none yet", "", "")
        stats.update(grid)
        fit.update(self._fit(rec))
        model = rec.model
        self._table(PARAMETER_COLUMNS, [parameter_cells(p) for p in (model.doc.get("parameters") or [])]
                    if model is not None else [])
        self._exports()

    def _verification(self, rec: Any) -> None:
        """An ISO 9283 pose test (``hil verify``): its figures, not a calibration's (it has no model)."""
        s = rec.summary
        doc = rec.result if isinstance(rec.result, dict) else {}
        results = doc.get("results") if isinstance(doc.get("results"), dict) else {}
        word = "VERIFIED" if s.status == "accepted" else s.status.upper()
        style = "bold white on green" if s.status == "accepted" else "bold reverse"
        line = Text.assemble((f" {word} ", style), "  ", (rec.id, "bold"),
                             f"  ISO 9283 pose test, {s.measured}/{s.planned} poses")  # whole at 80
        model = doc.get("model")
        source = str(model.get("source", "-")) if isinstance(model, dict) else str(model or "-")
        if source != "-":  # in full here (it wraps, never cut); the Test panel has its file name
            line.append(f"\n model {source}", "dim")
        if rec.detail:
            line.append(f"\n{rec.detail}", "dim")
        self.query_one("#verdict", Static).update(line)
        stats = self.query_one("#stats", Static)
        stats.border_title = "ISO 9283 worst pose, mm"
        grid = Table("", "AP", "RP", "AP mean", box=None, padding=(0, 1), show_edge=False)
        for mode, r in results.items():
            r = r if isinstance(r, dict) else {}
            grid.add_row(MODE_LABELS.get(str(mode), str(mode)), _mm(r.get("AP_max")),
                         _mm(r.get("RP_max")), _mm(r.get("AP_mean")))
        if not results:
            grid.add_row("no figures yet", "", "", "")
        stats.update(grid)
        fit = self.query_one("#fit", Static)
        fit.border_title = "Test"
        info = Table.grid(padding=(0, 1))
        info.add_column(style="dim")
        info.add_column()
        info.add_row("cycles", str(doc.get("cycles", "-")))
        info.add_row("status", status_words(s))  # "verified", as History and `hil history` say
        # the model's file name on a line of its own, the panel's whole width (half the screen less
        # border and padding): beside a label, at 80 columns, a model's path
        # ("out/20261127-161234-a1b8-model.json") was cut at its end, the part that names the file.
        # The verdict above has the whole path.
        width = max(12, self.size.width // 2 - 4) if self.size.width else 36
        name = shorten_middle(Path(source).name, width) if source != "-" else "none"
        fit.update(Group(info, Text("model", style="dim"), Text(name, no_wrap=True)))
        self._table(pose_columns([str(m) for m in results]), pose_rows(results))
        self._exports()

    @staticmethod
    def _fit(rec: Any) -> Table:
        grid = Table.grid(padding=(0, 1))
        grid.add_column(style="dim")
        grid.add_column()
        model = rec.model
        if model is None:
            grid.add_row("model", "none yet")
            return grid
        f = model.doc.get("fit") or {}
        grid.add_row("RMS", f"{_mm(f.get('rms'))} mm (max {_mm(f.get('max'))})")
        grid.add_row("poses", f"{f.get('used', '-')} used of {f.get('poses', '-')}, "
                              f"{len(f.get('rejected') or [])} rejected")
        by_role = _fitted_by_role(rec)
        if by_role:  # its own row: within the 25 columns the value has at 80
            grid.add_row("", by_role)
        cond = f.get("condition")
        grid.add_row("condition", f"{cond:.3g}" if isinstance(cond, int | float) else "-")
        grid.add_row("parameters", str(len(model.doc.get("parameters") or [])))
        return grid

    def _exports(self) -> None:
        text = Text()
        if self.written:
            folders = {str(Path(p).parent) for p in self.written}
            text.append(f"wrote in {', '.join(sorted(folders))}: ", "dim")
            text.append("  ".join(Path(p).name for p in self.written))
        if self.export_error:
            text.append(("\n" if self.written else "") + f"export failed: {self.export_error}", "bold red")
        if not text:
            text.append(f"exports go to {self.hil.session.options.out_dir}", "dim")
        self.query_one("#exports", Static).update(text)
