"""The campaign report: self-contained, well-formed, escaped HTML; the MES result's stable keys."""

from __future__ import annotations

import base64
import json
import re
import xml.etree.ElementTree as ET
from html.parser import HTMLParser

import numpy as np
import pinocchio as pin
import pytest

from hil.calibration.identification import identify, validate
from hil.calibration.measurements import Measurements
from hil.calibration.model_file import write_json
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from hil.campaign.acceptance import class_bound
from hil.campaign.events import Message, PoseSkipped, Resumed, Suspended
from hil.cli import main
from hil.report import (
    Observability,
    RobotIdentity,
    mes_result,
    render_html,
    report_data_from,
    report_data_from_result,
    summarise_events,
    write_report,
)
from hil.station.config import default_config

HOSTILE = '<script>alert("x")</script> & \'cell\''
MES_KEYS = {"format", "campaign", "station", "robot", "robot_serial", "robot_software", "passed",
            "accept_rms", "started", "finished", "validation", "fit", "observability", "times",
            "suspensions", "notes", "hashes", "software", "config", "model", "per_pose",
            "tracker_pose", "units"}


@pytest.fixture(scope="module")
def campaign():
    """A real identification of a simulated UR5e with one planted outlier, and its validation."""
    rng = np.random.default_rng(7)
    truth = random_truth("ur5e", rng, ideal=True)
    q, p = measure(truth, random_configurations("ur5e", 30, rng), Noise(), rng)
    p[4] += [4e-4, -3e-4, 2e-4]
    qv, pv = measure(truth, random_configurations("ur5e", 25, rng), Noise(), rng)
    cal = Measurements.from_arrays(q, p, "cal.csv")
    val = Measurements.from_arrays(qv, pv, "val.csv")
    fit = identify(cal, "ur5e")
    return fit, cal, val, validate(fit.baseline, val), validate(fit.geometry, val)


def build(campaign, accept=1e-4, station="Cell 4", **kw):
    fit, cal, val, before, after = campaign
    config = default_config().with_overrides(station__name=station)
    events = [Suspended(campaign="c", kind="beam_lost", message="Beam lost: <re-lock> & retry"),
              Resumed(campaign="c", kind="beam_lost", waited=3.5),
              PoseSkipped(campaign="c", index=3, role="calibration", reason="unreachable <x>"),
              Message(campaign="c", level="info", text="not shown")]
    args = dict(campaign="C-0042", robot=RobotIdentity("ur5e", "2023<5500>123", software="5.15"),
                started=1.7e9, finished=1.7e9 + 600, accept_rms=accept, calibration=cal,
                validation=val, iso9283={"AP": 3e-5, "RP": 1e-5},
                observability=Observability("O1", 0.97, 1.0, "tabu"),
                times={"motion": 300.0, "settle": 20.0, "measure": 90.0, "compute": 1.5}, events=events)
    args.update(kw)
    return report_data_from(fit, before, after, config, **args)


@pytest.fixture(scope="module")
def data(campaign):
    return build(campaign, station=HOSTILE)


@pytest.fixture(scope="module")
def page(data):
    return render_html(data, generated="2024-01-01T00:00:00+00:00")


def xml_of(page: str) -> ET.Element:
    assert page.startswith("<!DOCTYPE html>\n")
    return ET.fromstring(page.split("\n", 1)[1])


class _Collector(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict[str, str | None]]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))


def test_html_is_well_formed_xml_and_html(page):
    root = xml_of(page)
    assert root.tag == "html"
    assert root.find("head/title") is not None
    parser = _Collector()
    parser.feed(page)
    parser.close()
    assert any(tag == "table" for tag, _ in parser.tags)


def test_self_contained_no_external_resources(page):
    parser = _Collector()
    parser.feed(page)
    for tag, attrs in parser.tags:
        assert tag not in ("script", "link", "iframe", "object", "embed"), tag
        for name in ("src", "href"):
            if attrs.get(name) is not None:
                assert attrs[name].startswith(("data:", "#")), (tag, attrs[name][:60])
    assert "http://" not in page and "https://" not in page
    assert "@import" not in page and "url(" not in page


def test_plots_are_embedded_pngs(page):
    uris = [el.get("src") for el in xml_of(page).iter("img")]
    assert len(uris) >= 4  # per-pose validation, histograms, per-axis, calibration residuals
    for uri in uris:
        assert uri.startswith("data:image/png;base64,")
        assert base64.b64decode(uri.split(",", 1)[1]).startswith(b"\x89PNG\r\n\x1a\n")
    assert all(el.get("alt") for el in xml_of(page).iter("img"))


def test_hostile_strings_are_escaped(page):
    assert "<script" not in page
    assert "&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt; &amp; &#x27;cell&#x27;" in page
    assert "2023&lt;5500&gt;123" in page
    assert "Beam lost: &lt;re-lock&gt; &amp; retry" in page
    assert "unreachable &lt;x&gt;" in page
    text = "".join(xml_of(page).itertext())
    assert HOSTILE in text  # and it still reads as the user wrote it


def verdict(page: str) -> str:
    (div,) = [d for d in xml_of(page).iter("div") if "verdict" in (d.get("class") or "")]
    return div.get("class").split()[1], "".join(div.itertext())


def test_pass_and_fail_are_shown(campaign, page):
    cls, text = verdict(page)
    assert cls == "pass" and "PASS" in text and "FAIL" not in text
    failed = build(campaign, accept=1e-6)
    assert not failed.passed
    cls, text = verdict(render_html(failed))
    assert cls == "fail" and "FAIL" in text and "PASS" not in text
    assert "0.001 mm" in text  # the threshold, in mm


def test_every_parameter_and_section_is_shown(data, page):
    fit = data.parameters
    assert len(fit) == 27
    cells = {"".join(td.itertext()) for td in xml_of(page).iter("td")}
    for p in fit:
        assert p.name in cells
    assert any(u in cells for u in ("mm", "mrad"))
    for ident in ("validation", "calibration", "parameters", "correlated", "rejected", "observability",
                  "campaign", "config", "provenance"):
        assert f'id="{ident}"' in page
    assert data.rejected and data.rejected[0].index == 4
    assert str(data.rejected[0].line) in cells  # the file line of the rejected pose
    for value in data.hashes.values():
        assert value in page
    headers = {"".join(th.itertext()) for th in xml_of(page).iter("th")}
    assert {"robot.speed", "campaign.acceptance", "station.name"} <= headers  # station config
    assert "pinocchio" in page and "motion" in page and "97.0 %" in page


def test_report_data_from_defaults(campaign):
    fit, _, _, before, after = campaign
    d = report_data_from(fit, before, after, default_config(), campaign="x")
    # no campaign.acceptance by default: the robot class's bound (hil.campaign.acceptance)
    assert default_config().get("campaign.acceptance") is None
    assert d.accept_rms == class_bound("ur5e")
    assert d.calibration_before is None and d.validation_after.vectors is None
    assert d.model["format"] == "hil-model/1"
    page = render_html(d)
    assert "Not recorded for this campaign" in page  # observability
    captions = ["".join(c.itertext()) for c in xml_of(page).iter("figcaption")]
    assert len(captions) == 4
    assert any("per-axis validation errors were not recorded" in c for c in captions)


def test_events_are_summarised():
    s, notes = summarise_events([
        Suspended(campaign="c", kind="protective_stop", message="clear the cell"),
        Suspended(campaign="c", kind="beam_lost", message="re-lock"),
        Resumed(campaign="c", kind="beam_lost", waited=2.0),
        Message(campaign="c", level="warning", text="drift"),
    ])
    assert [(x.kind, x.waited) for x in s] == [("protective_stop", None), ("beam_lost", 2.0)]
    assert notes == ("warning: drift",)


def test_mes_result_keys_and_round_trip(data, tmp_path):
    doc = mes_result(data)
    assert set(doc) == MES_KEYS
    text = json.dumps(doc, allow_nan=False)  # strict JSON
    doc = json.loads(text)
    assert doc["format"] == "hil-result/1"
    assert doc["campaign"] == "C-0042" and doc["station"] == HOSTILE
    assert (doc["robot"], doc["robot_serial"]) == ("ur5e", "2023<5500>123")
    assert doc["passed"] is True and doc["accept_rms"] == 1e-4
    assert set(doc["validation"]) == {"before", "after", "iso9283"}
    assert set(doc["validation"]["after"]) == {"count", "mean", "rms", "max"}
    assert doc["validation"]["after"]["rms"] == pytest.approx(data.validation_after.rms)
    assert doc["model"]["format"] == "hil-model/1" and len(doc["model"]["parameters"]) == 27
    assert doc["fit"]["rejected_lines"] == [r.line for r in data.rejected]
    assert doc["started"].startswith("2023-11-14T")
    assert doc["suspensions"][0]["waited"] == 3.5
    assert len(doc["per_pose"]["validation"]["after"]) == 25

    back = report_data_from_result(doc)
    assert back.passed == data.passed and back.station == data.station
    assert back.validation_after.rms == pytest.approx(data.validation_after.rms)
    assert np.allclose(back.validation_after.vectors, data.validation_after.vectors)
    assert [p.name for p in back.parameters] == [p.name for p in data.parameters]
    assert back.rejected == data.rejected and back.correlated == data.correlated
    assert render_html(back, generated="g") == render_html(data, generated="g")


def test_cli_rebuilds_a_report(data, tmp_path, capsys):
    result, out = tmp_path / "result.json", tmp_path / "report.html"
    doc = mes_result(data)
    del doc["per_pose"]  # an offline result as `hil calibrate --sim` writes today
    write_json(result, doc)
    assert main(["report", "--result", str(result), "--out", str(out)]) == 0
    page = out.read_text(encoding="utf-8")
    assert "not recorded in this result" in page and verdict(page)[0] == "pass"
    assert f"wrote {out}" in capsys.readouterr().err  # the one line every command writing a file prints
    write_json(result, {"format": "hil-result/1", "model": {"fit": {}}, "validation": 1,
                        "accept_rms": 1e-4, "passed": True})
    assert main(["report", "--result", str(result), "--out", str(tmp_path / "bad.html")]) == 2
    err = capsys.readouterr().err
    assert str(result) in err and len(err.strip().splitlines()) == 1


def test_write_report(data, tmp_path):
    path = write_report(data, tmp_path / "sub" / "r.html", generated="now")
    assert path.read_text(encoding="utf-8") == render_html(data, generated="now")
    assert not [p for p in path.parent.iterdir() if p.name != "r.html"]  # no temp file left
    assert re.search(r"validation RMS \d+\.\d{3} mm ≤ acceptance 0\.100 mm", path.read_text("utf-8"))


# --- issue 16: the report and the files ------------------------------------------------------------

def section(page: str, ident: str) -> ET.Element:
    (sec,) = [s for s in xml_of(page).iter("section") if s.get("id") == ident]
    return sec


def rows_of(table: ET.Element) -> list[list[str]]:
    return [["".join(td.itertext()) for td in tr] for tr in table.find("tbody")]


def test_wall_time_phases_sum_to_the_total(campaign):
    """`total` (wall time) and `retries` (a count) are not phases: the phases sum to the total."""
    times = {"motion": 3.98, "settle": 0.2, "joints": 0.54, "measure": 0.71, "suspended": 0.0,
             "compute": 15.89, "total": 22.95, "retries": 2.0}
    page = render_html(build(campaign, times=times))
    table = section(page, "campaign").find("table")
    rows = rows_of(table)
    phases = [r for r in rows if not r[0].startswith("total")]
    [total] = [r for r in rows if r[0].startswith("total")]
    names = [r[0] for r in phases]
    assert "retries" not in names and "total" not in names
    assert sum(float(r[1].removesuffix(" s")) for r in phases) == pytest.approx(22.95, abs=0.05 * len(phases))
    assert total[1] == f"{22.95:.1f} s"
    assert any(n.startswith("other") for n in names)  # 1.63 s no phase accounts for
    assert sum(float(r[2].removesuffix(" %")) for r in phases) == pytest.approx(100, abs=0.1 * len(phases))
    assert "pose visits retried after a suspension" in page and ">2<" in page


def test_the_wall_time_total_is_the_runs_own_total(campaign):
    """The engine's ``events_in_motion`` is time inside ``motion`` (a point's commit while the arm
    travels), not a phase of its own: counted again, the phases outgrew ``times.total`` and the report
    showed their sum as the total (87.3 s for a run of 86.5 s)."""
    times = {"motion": 74.61, "settle": 0.0, "joints": 0.02, "measure": 5.51, "suspended": 0.0,
             "compute": 3.31, "events": 0.63, "events_in_motion": 3.25, "total": 86.46, "retries": 0.0}
    page = render_html(build(campaign, times=times))
    rows = rows_of(section(page, "campaign").find("table"))
    phases = [r for r in rows if not r[0].startswith("total")]
    [total] = [r for r in rows if r[0].startswith("total")]
    assert total[1] == "86.5 s"
    assert "events_in_motion" not in [r[0] for r in phases]
    assert sum(float(r[1].removesuffix(" s")) for r in phases) == pytest.approx(86.46, abs=0.05 * len(phases))
    # said where it belongs: part of the motion
    assert "3.2 s of it delivering events while the arm travelled" in "".join(
        section(page, "campaign").itertext())


def test_tracker_pose_in_plain_terms(campaign, data, page):
    """The tracker is reported as x, y, z (mm) and roll, pitch, yaw (deg); tx…rz only as log coords."""
    fit = campaign[0]
    T = fit.geometry.tracker
    xyz, rpy = T.translation, pin.rpy.matrixToRpy(T.rotation)
    sec = section(page, "parameters")
    tables = list(sec.iter("table"))
    placement = next(t for t in tables if "".join(t.find("thead").itertext()).startswith("tracker"))
    got = {r[0]: (float(r[1]), r[3]) for r in rows_of(placement)}
    for k, axis in enumerate("xyz"):
        assert got[axis] == (pytest.approx(xyz[k] * 1e3, abs=1e-3), "mm")
    for k, angle in enumerate(("roll", "pitch", "yaw")):
        assert got[angle] == (pytest.approx(np.degrees(rpy[k]), abs=1e-3), "deg")
    # the log coordinates are in a table that says so, and only there
    for t in tables:
        names = [r[0] for r in rows_of(t)]
        if any(n.startswith("tracker.") for n in names):
            assert "se(3) log" in "".join(t.find("thead").itertext())
            assert all(n.startswith("tracker.") for n in names)

    # the result: the same pose with its σ, plus the model's own block, and labelled parameters
    doc = json.loads(json.dumps(mes_result(data)))
    tp = doc["tracker_pose"]
    assert tp["xyz"] == pytest.approx(xyz) and tp["rpy"] == pytest.approx(rpy)
    assert doc["model"]["tracker_pose"] == tp and "log" in doc["model"]["parameter_coordinates"]
    names = list(fit.names)
    sel = [names.index(f"tracker.{a}") for a in ("tx", "ty", "tz")]
    cov_v = fit.covariance[np.ix_(sel, sel)]
    R = T.rotation  # T·exp(δ): the position moves by R·v to first order
    assert tp["xyz_std"] == pytest.approx(np.sqrt(np.diag(R @ cov_v @ R.T)), rel=1e-3)
    assert all(s > 0 for s in tp["rpy_std"])
    # an older result without the block: the same pose, computed from the geometry and covariance
    del doc["model"]["tracker_pose"], doc["tracker_pose"]
    back = report_data_from_result(doc)
    assert back.tracker_pose["xyz"] == pytest.approx(tp["xyz"])
    assert back.tracker_pose["xyz_std"] == pytest.approx(tp["xyz_std"], rel=1e-6)


def _figures(monkeypatch) -> list:
    import hil.report.plots as plots

    drawn = []
    real = plots.png

    def keep(fig):
        drawn.append(fig)
        return real(fig)

    monkeypatch.setattr(plots, "png", keep)
    return drawn


def test_before_calibration_is_one_figure_and_campaign_poses_are_poses(campaign, monkeypatch):
    """"Before calibration" is the nominal arm with the tracker and SMR fitted, in the table and in
    the plot alike; the fit's starting RMS is labelled as such; campaign poses are labelled "pose"."""
    drawn = _figures(monkeypatch)
    d = build(campaign, line_kind="pose")
    page = render_html(d)
    kv = {"".join(tr.find("th").itertext()): "".join(tr.find("td").itertext())
          for tr in section(page, "calibration").iter("tr")}
    before = [v for k, v in kv.items() if "before" in k.lower()]
    assert before == [f"{d.calibration_before.rms * 1e3:.3f} mm"]
    start = [k for k, v in kv.items() if v == f"{d.fit.initial_rms * 1e3:.3f} mm"]
    assert start and all("start of the fit" in k for k in start)
    axes = [ax for fig in drawn for ax in fig.axes]
    legends = [t.get_text() for ax in axes if ax.get_legend() for t in ax.get_legend().get_texts()]
    assert f"before calibration (RMS {d.calibration_before.rms * 1e3:.3f} mm)" in legends
    labels = [ax.get_xlabel() for ax in axes if "pose" in ax.get_xlabel()]
    assert {"calibration pose", "validation pose"} <= set(labels)
    assert not any("input line" in x for x in labels)
    ticks = [[t.get_text() for t in ax.get_xticklabels()] for ax in axes
             if ax.get_xlabel() == "validation pose"]
    assert ticks and all(t[0] == str(campaign[2].lines[0]) for t in ticks)  # the poses' own names
    rejected = rows_of(section(page, "rejected").find("table"))
    assert rejected[0][0] == str(d.rejected[0].line)  # named by its pose number, no "file line"
    assert "file line" not in "".join(section(page, "rejected").itertext())

    # a file's poses keep their input lines; a saved campaign result reads back as poses
    drawn.clear()
    render_html(build(campaign))
    assert {"calibration pose (input line)", "validation pose (input line)"} <= {
        ax.get_xlabel() for f in drawn for ax in f.axes}
    doc = mes_result(d)
    assert doc["per_pose"]["calibration"]["line_kind"] == "pose"
    assert doc["per_pose"]["validation"]["lines"] == campaign[2].lines.tolist()
    del doc["per_pose"]["calibration"]["line_kind"]  # older results: a campaign's all the same
    assert report_data_from_result(doc).line_kind == "pose"


def test_result_states_its_units(data):
    doc = mes_result(data)
    assert doc["units"]["length"] == "m" and doc["units"]["angle"] == "rad" and doc["units"]["time"] == "s"


def test_report_of_an_unfinished_campaign_says_so(tmp_path, capsys):
    result = tmp_path / "result.json"
    write_json(result, {"format": "hil-result/1", "campaign": "20261122-133724-c0ce", "passed": False,
                        "station": "s", "robot": "ur5e", "status": "aborted", "exit_code": 4,
                        "error": "Aborted: operator abort", "tracker": {}, "robot_info": {}})
    assert main(["report", "--result", str(result), "--out", str(tmp_path / "r.html")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert str(result) in err and "did not finish" in err and "'aborted'" in err
    assert "no calibrated model" in err and "missing field" not in err
    assert not (tmp_path / "r.html").exists()


def test_the_acceptance_threshold_is_drawn_only_against_the_rms_after_calibration(campaign, monkeypatch):
    """The nominal arm's deviations (the "before" bars, millimetres) are not judged by the acceptance
    threshold (on the validation RMS after calibration): the per-pose chart of both draws no
    acceptance line; the histograms draw it on the "after" panel only."""
    import hil.report.plots as plots
    import hil.report.render as render

    seen: dict[str, dict] = {}
    original_bars, original_hist = plots.errors_per_pose, plots.histograms

    def bars(*args, **kwargs):
        seen.setdefault("bars", kwargs)
        return original_bars(*args, **kwargs)

    def hist(*args, **kwargs):
        seen.setdefault("hist", kwargs)
        return original_hist(*args, **kwargs)

    monkeypatch.setattr(render, "errors_per_pose", bars)
    monkeypatch.setattr(render, "histograms", hist)
    render_html(build(campaign), generated="2024-01-01T00:00:00+00:00")
    assert seen["bars"].get("accept_rms") is None
    assert seen["hist"].get("accept_rms") == pytest.approx(1e-4)
