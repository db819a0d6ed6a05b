"""One source for each count and time a campaign's outputs show ("Day one, second round", item 5).

* Bootstrap poses: ``campaign.bootstrap_poses`` moves of the arm plus the wrist turns — a config saying 6
  measures 10; the console, the result, the report and the store say so, from the plan's own count.
* The fit's poses are the bootstrap's and the calibration poses: the report says which, from the
  result's ``poses`` block (the plan's counts), never "40 calibration poses" for 10 + 30.
* The identified parameter count: the chooser's ``identified_parameters`` is the fit's own
  (compliance included), beside the parameters the selection served.
* The campaign's end is its RunFinished's time, not the time its report was made.
* A campaign interrupted during its bootstrap has 0 campaign poses planned and its bootstrap points
  stored: the store's summary carries them (``bootstrap_planned``, ``bootstrap_measured``).
"""

from __future__ import annotations

import datetime as dt
import html
import time

import numpy as np

from hil.campaign.calibration_plan import bootstrap_targets
from hil.campaign.chooser import campaign_chooser
from hil.campaign.events import PhaseChanged, PlanReady, RunFinished
from hil.report import render_html, report_data_from_result
from hil.report.result import result_document
from tests.hil.campaign.test_resume_and_fail_fast import BootCell


def test_every_output_counts_the_campaigns_poses_from_its_plan(tmp_path):
    cell = BootCell(tmp_path)
    outcome = cell.run()
    assert outcome.status in ("accepted", "rejected"), outcome.error
    boot = len(bootstrap_targets(np.zeros(6), cell.config.campaign["bootstrap_poses"]))
    assert cell.config.campaign["bootstrap_poses"] == 6 and boot == 10
    # the console's bootstrap line says how many and why not the config's 6
    (phase,) = [e for e in cell.of(PhaseChanged) if e.phase == "bootstrap"]
    assert "10 bootstrap poses (6 small moves of the arm, 4 turns of the wrist)" in phase.detail
    counts = outcome.result.counts
    measured = {role: sum(1 for r in outcome.result.records if r.role == role)
                for role in ("bootstrap", "calibration", "validation")}
    assert counts == {"bootstrap": {"planned": 10, "measured": measured["bootstrap"]},
                      "calibration": {"planned": 12, "measured": measured["calibration"]},
                      "validation": {"planned": 4, "measured": measured["validation"]}}
    boot, cal = measured["bootstrap"], measured["calibration"]
    assert boot == 10
    doc = result_document(outcome, cell.config, cell.events, time.time() - 5, None)
    assert doc["poses"] == counts
    assert doc["fit"]["poses"] == boot + cal  # the fit's poses are the bootstrap's and the calibration's
    # the campaign ended when its run did, whenever the result is made
    (end,) = cell.of(RunFinished)
    assert doc["finished"] == dt.datetime.fromtimestamp(end.t, dt.UTC).isoformat(timespec="seconds")
    for data in (report_data_from_result(doc, "r.json"),):
        page = html.unescape(render_html(data))
        assert f"{boot + cal} fitted: 10 bootstrap + {cal} calibration" in page
        assert f"{boot + cal} calibration poses" not in page
        assert "bootstrap poses (locate the tracker; fitted too): measured of planned" in page
        assert data.finished == doc["finished"] and f"→ {doc['finished']}" in page
    # the store's summary of the finished campaign
    summary = cell.store.campaign(cell.campaign).summary
    assert (summary.planned, summary.measured) == (16, cal + measured["validation"])
    assert (summary.bootstrap_planned, summary.bootstrap_measured) == (10, 10)


def test_a_campaign_interrupted_in_its_bootstrap_has_its_bootstrap_points_in_the_summary(tmp_path):
    cell = BootCell(tmp_path)
    outcome = cell.run(interrupt_after=3)
    assert outcome.status == "interrupted"
    summary = cell.store.campaign(cell.campaign).summary
    # no campaign pose is planned yet ("0 of ?"), but 3 of the 10 bootstrap poses are stored
    assert (summary.planned, summary.measured) == (0, 0)
    assert (summary.bootstrap_planned, summary.bootstrap_measured) == (10, 3)
    assert summary.as_dict()["bootstrap_measured"] == 3


def test_the_chooser_says_how_many_parameters_the_fit_identifies(tmp_path):
    """The selection serves the parameters its SMR guess makes observable; the fit identifies its own
    set (compliance included): the Plan screen compared the first with the geometry's 27."""
    from hil.station.config import minimum_calibration_poses

    cell = BootCell(tmp_path)
    config = cell.config.with_overrides(campaign__candidates=1500, campaign__calibration_poses=14)
    cell.config = config
    cell.choose = campaign_chooser(config)
    outcome = cell.run()
    assert outcome.status in ("accepted", "rejected"), outcome.error
    (plan,) = cell.of(PlanReady)
    info = plan.selection["calibration"]
    fitted = len(outcome.result.model["parameters"])
    assert config.campaign["compliance"] and fitted > 27  # the joints' compliances too
    assert info["identified_parameters"] == fitted
    assert fitted == minimum_calibration_poses(config.robot["type"], True, config.payload, config.gravity)[1]
    assert info["parameters"] + len(info["unobservable"]) == fitted
