"""Campaign reports: the self-contained HTML report and the JSON result for a plant's MES.

Typical use at the end of a campaign::

    data = report_data_from(fit, before, after, config, campaign=cid, calibration=meas,
                            validation=held_out, times=times, events=log)
    write_report(data, "report.html")
    write_json("result.json", mes_result(data))

`report_data_from_result` rebuilds the same `ReportData` from a saved result (``hil report``).

`hil.report.result` builds the ``hil-result/1`` document of a finished campaign (CLI and TUI alike).
`hil.report.fleet` is the fleet report (``hil fleet-report``), read from the store (`hil.store.fleet`).
`hil.report.verification` is the report of an ISO 9283 pose test (``hil verify --report``, ``hil report``
of its result); its tables and figure (`hil.report.pose_test`) are also the pose-test section of a
``hil calibrate --verify`` campaign's report. `hil.report.html` holds the blocks every page shares.

May import: `hil.verify`, `hil.store`, `hil.campaign`, `hil.station`, `hil.calibration`, `hil.arm`,
`hil.files`, `hil.errors`.
"""

from hil.report.data import (
    RESULT_FORMAT,
    ErrorSet,
    FitSummary,
    Observability,
    Parameter,
    ReportData,
    RobotIdentity,
    Suspension,
    report_data_from,
    report_data_from_result,
    summarise_events,
)
from hil.report.mes import mes_result
from hil.report.render import render_html, write_report

__all__ = [
    "RESULT_FORMAT",
    "ErrorSet",
    "FitSummary",
    "Observability",
    "Parameter",
    "ReportData",
    "RobotIdentity",
    "Suspension",
    "mes_result",
    "render_html",
    "report_data_from",
    "report_data_from_result",
    "summarise_events",
    "write_report",
]
