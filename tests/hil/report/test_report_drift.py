"""The report's warm-up and drift section: the plot, the flag beside (never instead of) the verdict, the
result's ``drift`` block and a report rebuilt from it."""

from __future__ import annotations

import html
import io
import re

import numpy as np
import pytest
from matplotlib.image import imread

from hil.calibration.identification import identify, validate
from hil.calibration.measurements import Measurements
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from hil.campaign.events import DriftFlagged, WarmupFinished
from hil.errors import InputError
from hil.report import mes_result, render_html, report_data_from, report_data_from_result, summarise_events
from hil.report.plots import drift_plot
from hil.station.config import default_config


@pytest.fixture(scope="module")
def campaign():
    rng = np.random.default_rng(3)
    truth = random_truth("ur5e", rng, rigid=True)
    q, p = measure(truth, random_configurations("ur5e", 30, rng), Noise(), rng)
    qv, pv = measure(truth, random_configurations("ur5e", 20, rng), Noise(), rng)
    cal, val = Measurements.from_arrays(q, p, "cal.csv"), Measurements.from_arrays(qv, pv, "val.csv")
    fit = identify(cal, "ur5e")
    return fit, cal, val, validate(fit.baseline, val), validate(fit.geometry, val)


def drift_block(flagged: bool, temperatures: bool = True) -> dict:
    """A ``drift`` block as `ReferenceWatch.summary` writes it: a warm-up of run 1 interrupted, run 2's
    warm-up and drift watch (the last point beyond the limit when `flagged`)."""
    series, seq = [], 0
    for run, phases in ((1, ["warmup"] * 3), (2, ["warmup"] * 6 + ["drift"] * 4)):
        for k, phase in enumerate(phases):
            seq += 1
            t = 130.0 * k
            growth = 60e-6 * np.exp(-t / 900.0)
            drift = growth if phase == "warmup" else 5e-6 * (k - 6)
            if flagged and phase == "drift" and k == len(phases) - 1:
                drift = 45e-6
            series.append({"seq": seq, "run": run, "phase": phase, "elapsed": t, "time": 1.7e9 + seq,
                           "q": [0.0] * 6, "xyz": [2.0, 0.0, 0.3], "moved": 2e-6, "drift": drift,
                           "baseline": run == 2 and k == 5,
                           "temperatures": [25.0 + 0.01 * t + j for j in range(6)] if temperatures else None})
    drifts = [s["drift"] for s in series if s["phase"] == "drift"]
    return {"reference": [0.0] * 6, "every": 10, "limit": 30e-6, "max": max(drifts),
            "flagged": max(drifts) > 30e-6, "baseline": 9, "series": series,
            "warmup": {"enabled": True, "interval": 120.0, "limit": 10e-6, "max_time": 3600.0, "ran": True,
                       "seconds": 650.0, "converged": True, "reason": "", "remaining": 4e-6,
                       "time_constant": 210.0,
                       "runs": [{"run": 1, "seconds": 260.0, "converged": False, "references": 3},
                                {"run": 2, "seconds": 650.0, "converged": True, "references": 6}]}}


def build(campaign, drift, events=()):
    fit, cal, val, before, after = campaign
    return report_data_from(fit, before, after, default_config(), campaign="C-7", calibration=cal,
                            validation=val, drift=drift, accept_rms=1e-3, events=events)


def section(page: str) -> str:
    match = re.search(r'<section id="drift">.*?</section>', page, re.S)
    assert match, "no warm-up and drift section"
    return html.unescape(match.group(0))


def test_a_flagged_campaign_says_so_beside_its_verdict_which_stays_the_validations(campaign):
    data = build(campaign, drift_block(flagged=True))
    assert data.passed and data.drift_flagged
    page = render_html(data, generated="2024-01-01T00:00:00+00:00")
    header = page[page.index("<header>"):page.index("</header>")]
    assert "PASS" in header and "DRIFT FLAGGED" in header and "45.0 µm" in header
    body = section(page)
    assert "YES — the accept/reject verdict above is still the validation's" in body
    assert body.count("<img") == 1 and "drift limit" not in body.split("<img")[0][-20:]
    assert "warm-up of run 1" in body and "did not settle" in body  # each run's warm-up
    assert "Reference drift" in page  # the summary tile


def test_an_unflagged_campaign_shows_the_section_without_a_flag(campaign):
    page = render_html(build(campaign, drift_block(flagged=False, temperatures=False)))
    assert "DRIFT FLAGGED" not in page and "<b>no</b>" not in section(page)
    assert ">no<" in section(page)


def test_no_drift_block_no_section(campaign):
    page = render_html(build(campaign, None))
    assert 'id="drift"' not in page and "Reference drift" not in page


def test_the_result_carries_the_drift_block_and_a_report_rebuilt_from_it_shows_it(campaign):
    block = drift_block(flagged=True)
    doc = mes_result(build(campaign, block))
    assert doc["drift"]["flagged"] and doc["drift"]["max"] == pytest.approx(45e-6)
    assert len(doc["drift"]["series"]) == len(block["series"]) and doc["passed"]
    again = report_data_from_result(doc, "r.json")
    assert again.drift_flagged and again.drift["series"] == doc["drift"]["series"]
    assert "DRIFT FLAGGED" in render_html(again)
    # an older result has no drift block: no section
    del doc["drift"]
    assert report_data_from_result(doc, "r.json").drift is None


@pytest.mark.parametrize(("change", "field"), [
    (lambda d: d.update(drift=[1, 2]), "'drift' must be an object"),
    (lambda d: d["drift"].update(series="x"), "'drift.series' must be a list"),
    (lambda d: d["drift"]["series"][2].update(drift="far"), "'drift.series[2]'"),
    (lambda d: d["drift"]["series"][0].pop("elapsed"), "'drift.series[0]'"),
    (lambda d: d["drift"].update(limit="30 µm"), "'drift.limit' must be a number"),
])
def test_a_malformed_drift_block_is_refused_naming_the_field(campaign, change, field):
    doc = mes_result(build(campaign, drift_block(flagged=False)))
    change(doc)
    with pytest.raises(InputError, match=re.escape(field)) as exc:
        report_data_from_result(doc, "r.json")
    assert str(exc.value).startswith("r.json: field ")


def test_the_drift_plot_is_a_picture_of_both_runs():
    for temperatures in (True, False):
        png = drift_plot(drift_block(flagged=True, temperatures=temperatures))
        image = imread(io.BytesIO(png), format="png")
        assert png[:8] == b"\x89PNG\r\n\x1a\n" and image.shape[1] > 1000
        assert image.shape[0] > (500 if temperatures else 380)  # the temperatures' panel below


def test_the_report_states_the_warm_up_rule_the_campaign_applied_with_its_figures(campaign):
    """The campaign judges "warm" by the first-order fit of the whole series (`ReferenceWatch.settled`):
    drift still to come below the limit, over a series spanning three fitted time constants. The
    report states that rule and the figures it judged, never "two consecutive measurements"."""
    body = section(render_html(build(campaign, drift_block(flagged=False))))
    assert "two consecutive" not in body
    assert "first-order fit" in body
    # run 2's series: 6 measurements over 650 s; τ = 210 s, so three time constants are 630 s
    assert "about 4.0 µm of drift still to come (limit 10.0 µm)" in body
    assert "the series spans 10.8 min, three fitted time constants 10.5 min (τ = 3.5 min)" in body
    # a warm-up that ended at max_time says why, with the same figures
    block = drift_block(flagged=False)
    block["warmup"].update(converged=False, remaining=25e-6, time_constant=900.0,
                           reason="still moving beyond the limit at max_time")
    body = section(render_html(build(campaign, block)))
    assert "no — still moving beyond the limit at max_time; measured anyway" in body
    assert "about 25.0 µm of drift still to come (limit 10.0 µm)" in body
    assert "three fitted time constants 45.0 min" in body


def test_the_warm_up_figures_of_a_result_read_back_are_the_same(campaign):
    block = drift_block(flagged=False)
    block["warmup"]["span"] = 650.0
    doc = mes_result(build(campaign, block))
    again = section(render_html(report_data_from_result(doc, "r.json")))
    assert "the series spans 10.8 min" in again


def test_the_notes_say_an_unsettled_warm_up_and_a_flag():
    notes = summarise_events([
        WarmupFinished(campaign="c", seconds=3600.0, converged=False, references=30, remaining=2e-5,
                       limit=1e-5),
        WarmupFinished(campaign="c", seconds=900.0, converged=True, references=8, remaining=2e-6, limit=1e-5),
        DriftFlagged(campaign="c", drift=4e-5, limit=3e-5, elapsed=1200.0, seq=12)])[1]
    assert len(notes) == 2
    assert notes[0].startswith("warning: warm-up stopped after 60.0 min without settling")
    assert notes[1].startswith("WARNING: drift: the reference moved 40.0 µm")
