"""Issue 14: the report and the result show the controller's own model beside hil's.

A tile and a validation row with its figures on the held-out poses, its DH table (nominal + delta)
with its checksums and calibration status; the result's ``validation`` block gains ``controller``
(added, nothing renamed) and a report rebuilt from the result shows the same.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from hil.calibration.identification import ErrorStats
from hil.calibration.model_file import model_document
from hil.report import mes_result, render_html, report_data_from_result
from hil.report.render import CONTROLLER_MEANS
from tests.hil.report.test_report import build, campaign, rows_of, section, xml_of  # noqa: F401

BLOCK = {"delta_theta": [1e-4, -2e-4, 0.0, 0.0, 0.0, 3e-4], "delta_a": [0.0, 2.5e-4, -1e-4, 0.0, 0.0, 0.0],
         "delta_d": [1e-4, 0.25, -0.2502, 2e-4, 0.0, 0.0], "delta_alpha": [0.0, 1e-3, 0.0, 0.0, 0.0, 0.0],
         "checksum": [101, 202, 303, 404, 505, 4294967295], "calibration_status": 3}


@pytest.fixture(scope="module")
def with_controller(campaign):  # noqa: F811 (the fixture imported above)
    fit, _cal, val, _before, after = campaign
    theirs = ErrorStats.of(np.full((len(val), 3), 4e-4 / np.sqrt(3)))  # 0.4 mm at every pose
    model = model_document(fit, after.as_dict(), controller=BLOCK)
    return build(campaign, validation_controller=theirs, model=model), theirs


def test_the_report_shows_the_controllers_figures_and_its_dh_table(with_controller):
    data, theirs = with_controller
    page = render_html(data, generated="2024-01-01T00:00:00+00:00")
    xml_of(page)  # still well-formed
    assert "Controller's own model" in page and "0.400 mm" in page  # the tile
    rows = rows_of(section(page, "validation").find(".//table"))
    assert [CONTROLLER_MEANS, str(theirs.count), "0.400 mm", "0.400 mm", "0.400 mm"] in rows
    dh = rows_of(section(page, "controller").find(".//table"))
    assert [r[0] for r in dh] == [f"joint {j}" for j in range(1, 7)]
    # joint 2: θ 0°, δθ −0.2 mrad, a −425 mm, δa 0.25 mm, d 0, δd 250 mm, α 0°, δα 1 mrad, checksum
    assert dh[1] == ["joint 2", "0.0000°", "-0.2000", "-425.0000", "0.2500", "0.0000", "250.0000",
                     "0.0000°", "1.0000", "202"]
    assert dh[0][7] == "90.0000°" and dh[5][-1] == "4294967295"
    status = rows_of(section(page, "controller").findall(".//table")[1])
    assert status == [["calibration status", "3"]]


def test_the_result_adds_the_controller_and_a_rebuilt_report_shows_the_same(with_controller, tmp_path):
    data, theirs = with_controller
    doc = json.loads(json.dumps(mes_result(data)))
    assert set(doc["validation"]) == {"before", "after", "iso9283", "controller"}
    assert doc["validation"]["controller"] == pytest.approx(theirs.as_dict())
    assert doc["model"]["controller"] == BLOCK
    rebuilt = report_data_from_result(doc, "r.json")
    assert rebuilt.validation_controller is not None
    assert rebuilt.validation_controller.rms == pytest.approx(theirs.rms)
    assert rebuilt.controller == BLOCK
    again = render_html(rebuilt, generated="2024-01-01T00:00:00+00:00")
    assert rows_of(section(again, "controller").find(".//table")) == rows_of(
        section(render_html(data, generated="x"), "controller").find(".//table"))


def test_without_the_controllers_model_the_report_is_as_before(campaign):  # noqa: F811
    data = build(campaign)
    page = render_html(data, generated="2024-01-01T00:00:00+00:00")
    assert 'id="controller"' not in page and CONTROLLER_MEANS not in page
    assert set(mes_result(data)["validation"]) == {"before", "after", "iso9283"}
