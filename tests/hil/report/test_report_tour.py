"""The time-aware selection's prediction beside method 000's in the MES result (``observability.tour``,
only for that selection) and in the report, and a report rebuilt from the result shows the same."""

from __future__ import annotations

from hil.report import mes_result, render_html, report_data_from, report_data_from_result
from hil.report.data import Observability, tour_summary
from hil.station.config import default_config
from tests.hil.report.test_report_precision import campaign  # noqa: F401 (a fixture)

TIMED = {"method": "time-aware", "index": "O1", "value": 2e-4,
         "predicted": {"poses": 41, "robot_time": 139.7, "relative_error": 0.998},
         "seed_method": {"poses": 30, "robot_time": 213.0}, "plan_cache": {"key": "k", "reused": True}}


def _data(campaign, obs):  # noqa: F811
    fit, cal, val, before, after = campaign
    return report_data_from(fit, before, after, default_config(), campaign="c1", calibration=cal,
                            validation=val, observability=obs)


def test_a_time_aware_tour_is_reported_beside_method_000(campaign) -> None:  # noqa: F811
    tour = tour_summary(TIMED)
    assert tour == {"poses": 41, "robot_time": 139.7, "relative_error": 0.998, "seed_poses": 30,
                    "seed_robot_time": 213.0, "reused": True}
    doc = mes_result(_data(campaign, Observability("O1", 2e-4, None, "time-aware", tour)))
    assert doc["observability"]["tour"] == tour
    rebuilt = report_data_from_result(doc)
    assert rebuilt.observability.tour == tour
    html = render_html(rebuilt)
    assert "41 poses, 139.7 s of robot time predicted" in html
    assert "30 poses in their best tour, 213.0 s" in html
    assert "reused: chosen by an earlier campaign" in html and "140 s</b> vs 213 s" in html


def test_other_selections_keep_the_block_as_it_was(campaign) -> None:  # noqa: F811
    assert tour_summary({"method": "tabu", "value": 1e-4}) is None
    doc = mes_result(_data(campaign, Observability("O1", 2e-4, 3e-4, "tabu")))
    assert set(doc["observability"]) == {"index", "value", "bound", "percent", "method"}
    assert "robot time predicted" not in render_html(report_data_from_result(doc))
