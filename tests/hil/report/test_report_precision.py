"""The validation RMS's standard error in the MES result (``validation.precision``, only when known) and
in the report's verdict box, and a report rebuilt from the result shows the same."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from hil.calibration.identification import identify, validate
from hil.calibration.measurements import Measurements
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from hil.calibration.validation_precision import validation_precision
from hil.errors import InputError
from hil.report import mes_result, render_html, report_data_from, report_data_from_result
from hil.station.config import default_config


@pytest.fixture(scope="module")
def campaign():
    rng = np.random.default_rng(8)
    truth = random_truth("ur5e", rng, rigid=True)
    q, p = measure(truth, random_configurations("ur5e", 30, rng), Noise(), rng)
    qv, pv = measure(truth, random_configurations("ur5e", 8, rng), Noise(), rng)
    cal, val = Measurements.from_arrays(q, p, "cal.csv"), Measurements.from_arrays(qv, pv, "val.csv")
    fit = identify(cal, "ur5e")
    return fit, cal, val, validate(fit.baseline, val), validate(fit.geometry, val)


def _data(campaign, precision=None):
    fit, cal, val, before, after = campaign
    return report_data_from(fit, before, after, default_config(), campaign="c1", calibration=cal,
                            validation=val, validation_precision=precision)


def test_the_result_carries_the_block_and_a_rebuilt_report_shows_it(campaign) -> None:
    after = campaign[4]
    precision = validation_precision(after.errors, range(after.count), [0, 0, 1, 1, 2, 2, 3, 3])
    assert precision["rms_standard_error"] is not None and precision["design_effect"] is not None
    doc = mes_result(_data(campaign, precision))
    plain = mes_result(_data(campaign))
    assert doc["validation"]["precision"] == precision
    assert set(doc["validation"]) == set(plain["validation"]) | {"precision"}  # every old key, plus one
    assert "precision" not in plain["validation"]  # unknown: not written (older readers see the same)
    rebuilt = report_data_from_result(doc)
    assert rebuilt.validation_precision == precision
    line = f"± {precision['rms_standard_error'] * 1e6:.1f} µm (1 s.e., 4 clusters, design effect"
    assert line in render_html(rebuilt) and line in render_html(_data(campaign, precision))
    assert "1 s.e." not in render_html(report_data_from_result(plain))


@pytest.mark.parametrize(("change", "field"), [
    (lambda b: b.update(design=None), "validation.precision"),
    (lambda b: b.update(rms_standard_error="1 µm"), "validation.precision.rms_standard_error"),
    (lambda b: b.update(clusters=2.5), "validation.precision.clusters"),
])
def test_a_malformed_block_is_refused_naming_the_field(campaign, change, field) -> None:
    after = campaign[4]
    doc = mes_result(_data(campaign, validation_precision(after.errors, range(after.count))))
    bad = copy.deepcopy(doc)
    change(bad["validation"]["precision"])
    with pytest.raises(InputError, match=f"result.json: field '{field}'"):
        report_data_from_result(bad, source="result.json")
