"""What a finished campaign produces: the report's data and the ``hil-result/1`` document.

Shared by ``hil calibrate`` and the TUI, so both write exactly the same result file and report.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from hil.calibration.measurements import measurements_sha256
from hil.campaign.events import Event, jsonable
from hil.station.config import StationConfig


def report_data(outcome: Any, config: StationConfig, events: list[Event], started: float,
                verification: dict[str, Any] | None = None) -> Any:
    """The report's data of a finished campaign; `verification`: its pose test (``--verify``)."""
    from hil.campaign.calibration_plan import BOOTSTRAP, CALIBRATION, VALIDATION, measurements_of
    from hil.campaign.events import RunFinished
    from hil.report import RobotIdentity, report_data_from
    from hil.report.data import Observability, tour_summary

    r = outcome.result
    # the campaign ended when its run did (RunFinished), not when this report is made
    ends = [e.t for e in events if isinstance(e, RunFinished) and e.campaign == outcome.campaign]
    by_role: dict[str, list[Any]] = {BOOTSTRAP: [], CALIBRATION: [], VALIDATION: []}
    for rec in sorted(r.records, key=lambda x: x.index):
        by_role[rec.role].append(rec)
    fitted = by_role[BOOTSTRAP] + by_role[CALIBRATION]
    sel = r.selection.get("calibration") or {}
    obs = (Observability(sel.get("index", "O1"), float(sel["value"]), sel.get("bound"), sel.get("method", ""),
                         tour_summary(sel))
           if sel.get("value") is not None else None)
    iso = ({"AP (worst pose)": r.iso9283["AP_max"], "RP (worst pose)": r.iso9283["RP_max"]}
           if r.iso9283 else None)
    cal = measurements_of(fitted, "calibration")
    val = measurements_of(by_role[VALIDATION], "validation")
    # Every pose the campaign measured (fitted, then held out), hashed as one measurements CSV; the
    # calibration and validation sets are hashed on their own too (see `measurements_sha256`).
    digest = measurements_sha256(np.vstack([cal.q, val.q]), np.vstack([cal.p, val.p]))
    return report_data_from(
        r.fit, r.before, r.after, config, campaign=outcome.campaign,
        robot=RobotIdentity(config.robot["type"], outcome.robot_info.get("serial", ""),
                            outcome.robot_info.get("model", ""), outcome.robot_info.get("software", "")),
        started=started, finished=ends[-1] if ends else time.time(), calibration=cal, validation=val,
        iso9283=iso,
        observability=obs, times=outcome.timing, events=events,
        hashes={"measurements": digest}, model=r.model, line_kind="pose",
        validation_controller=r.controller, verification=verification, drift=r.drift,
        stopping=r.stopping, validation_precision=r.validation_precision,
        poses=r.counts or None,
        passed=None if r.verdict is None else r.verdict.passed,
        verdict=None if r.verdict is None else r.verdict.as_dict())


def result_document(outcome: Any, config: StationConfig, events: list[Event], started: float,
            truth: dict | None) -> dict[str, Any]:
    """The hil-result/1 document (the MES result when the campaign finished, else its status)."""
    if outcome.result is not None:
        from hil.report import mes_result

        doc = mes_result(report_data(outcome, config, events, started))
        if outcome.result.iso9283:
            doc["validation"]["iso9283_poses"] = outcome.result.iso9283["poses"]
        doc["selection"] = outcome.result.selection
        sweep = getattr(outcome.result, "sweep", None)
        if sweep is not None:  # a sweep campaign: its clock map, samples used and left out by reason
            doc["sweep"] = sweep
    else:
        doc = {"format": "hil-result/1", "campaign": outcome.campaign, "passed": False,
               "station": config.station["name"], "robot": config.robot["type"]}
    doc["status"] = outcome.status
    doc["exit_code"] = outcome.exit_code
    doc["error"] = None if outcome.error is None else f"{type(outcome.error).__name__}: {outcome.error}"
    doc["tracker"] = outcome.tracker_info
    doc["robot_info"] = outcome.robot_info
    if truth is not None:
        doc["truth"] = truth
    return jsonable(doc)
