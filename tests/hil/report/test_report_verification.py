"""The pose test in the calibration report (``hil calibrate --verify``): the verification report's own
tables and figure, with the document's numbers; the MES result keeps it (a key added, none changed) and
a saved result renders the same page; a test not run or not finished says so; a malformed block is one
line naming the field."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from hil.arm.kinematics import Kinematics
from hil.errors import InputError
from hil.report import mes_result, render_html, report_data_from_result
from hil.report.data import check_verification
from hil.report.render import fmt_mm
from hil.report.verification import render_verification
from hil.verify.result import evaluate, model_frame
from tests.hil.report.test_report import HOSTILE, MES_KEYS, build, campaign, rows_of, section, xml_of
from tests.hil.verify.station import cell
from tests.hil.verify.test_result import records_of

__all__ = ["campaign"]  # the calibration's fixture, shared with test_report.py

HEAD = ["pose", "n", "AP_x", "AP_y", "AP_z", "AP_P", "S_l", "RP_l"]


@pytest.fixture(scope="module")
def verification() -> dict:
    """A finished pose test of a simulated cell (both modes, 3 cycles), as hil calibrate --verify embeds
    it: the figures of `hil.verify.result.evaluate` and the run's provenance."""
    c = cell()
    design = c.design(cycles=3)
    records = records_of(design, Kinematics(c.truth), np.random.default_rng(1))
    doc = evaluate(design, records, model_frame(c.truth), {}, c.controller)
    doc.update({"campaign": "V-0007", "status": "accepted", "exit_code": 0, "error": None,
                "station": HOSTILE, "model": {"source": "campaign C-0042", "sha256": "ab" * 32},
                "compensated": True, "controller": {"reported": False, "note": "not reported"},
                "robot_info": {"model": "UR5e", "serial": "2023<5500>123"}, "software": "0"})
    doc["skipped"] = [{"index": 4, "mode": "uncompensated", "pose": "P3", "reason": HOSTILE}]
    return json.loads(json.dumps(doc))


@pytest.fixture(scope="module")
def page(campaign, verification) -> str:
    return render_html(build(campaign, verification=verification), generated="g")


def expected_rows(block: dict) -> list[list[str]]:
    return [[p["pose"], str(p["n"])] + [fmt_mm(p[k]) for k in HEAD[2:]] for p in block["poses"]]


def test_the_section_shows_the_verifications_tables_with_its_numbers(page, verification):
    names = [s.get("id") for s in xml_of(page).iter("section")]
    assert names[:3] == ["validation", "verification", "calibration"]  # right after the validation
    sec = section(page, "verification")
    tables = sec.findall("table")
    heads = ["".join(th.itertext()) for th in tables[0].find("thead/tr")]
    assert heads == HEAD
    # one table per mode, then the uncompensated poses in the controller's own frame, then the setup
    blocks = [*verification["results"].values(), verification["own_frame"]]
    for table, block in zip(tables, blocks, strict=False):
        assert rows_of(table) == expected_rows(block)
    assert len(tables) == len(blocks) + 1
    titles = ["".join(h.itertext()) for h in sec.iter("h3")]
    assert titles[0].startswith("uncompensated: ") and titles[1].startswith("compensated: ")
    assert "Test" in titles
    # the figure of the attained positions, and the visits measured
    assert len(sec.findall("figure")) == 1 and "attained positions" in sec.find("figure/img").get("alt")
    text = "".join(sec.itertext())
    assert "30 of 30 visits measured" in text and "verification campaign V-0007" in text
    assert HOSTILE in text  # the skipped visit's reason, escaped (the page parsed as XML)


def test_the_summary_has_each_modes_worst_ap_and_rp(page, verification):
    tiles = {"".join(t.find("div[@class='label']").itertext()): "".join(t.itertext())
             for t in xml_of(page).iter("div") if t.get("class") == "tile"}
    for mode, block in verification["results"].items():
        tile = tiles[f"Pose test AP {mode}"]
        assert fmt_mm(block["AP_max"]) in tile and f"RP {fmt_mm(block['RP_max'])}" in tile
    unc, comp = (verification["results"][m]["AP_max"] for m in ("uncompensated", "compensated"))
    assert comp < unc / 10  # the true model compensates what the controller's misses


def test_the_tables_are_the_verification_reports_own(page, verification):
    alone = render_verification(verification, generated="g")
    mine = [rows_of(t) for t in section(page, "verification").findall("table")]
    theirs = [rows_of(t) for t in section(alone, "results").findall("table")]
    assert mine[:len(theirs)] == theirs


def test_the_result_keeps_it_and_renders_the_same_page(campaign, verification, page):
    data = build(campaign, verification=verification)
    doc = json.loads(json.dumps(mes_result(data), allow_nan=False))
    assert set(doc) == MES_KEYS | {"verification"}  # a key added, none changed
    assert doc["verification"] == verification
    assert render_html(report_data_from_result(doc), generated="g") == page
    assert set(mes_result(build(campaign))) == MES_KEYS  # without --verify: as before


@pytest.mark.parametrize("block, says", [
    ({"status": "not run", "reason": "the calibration ended rejected"},
     "The pose test was not run: the calibration ended rejected."),
    ({"format": "hil-verification/1", "campaign": "V-1", "status": "interrupted", "exit_code": 130,
      "error": "RunInterrupted: SIGINT"}, "did not finish (status interrupted: RunInterrupted: SIGINT)"),
])
def test_a_test_without_figures_says_why(campaign, block, says):
    data = build(campaign, verification=block)
    page = render_html(data, generated="g")
    assert says in "".join(section(page, "verification").itertext())
    assert not [t for t in xml_of(page).iter("div") if t.get("class") == "tile"
                and "Pose test" in "".join(t.itertext())]
    assert report_data_from_result(mes_result(data)).verification == block


@pytest.mark.parametrize("path, value, field", [
    (("results", "compensated", "AP_max"), "0.1", "verification.results.compensated.AP_max"),
    (("results", "uncompensated", "poses", 2, "offsets"), [[0.0, 1.0]],
     "verification.results.uncompensated.poses[2].offsets"),
    (("results", "compensated", "poses", 0, "RP_l"), None, "verification.results.compensated.poses[0].RP_l"),
    (("own_frame", "poses"), {}, "verification.own_frame.poses"),
    (("results",), [], "verification.results"),
])
def test_a_malformed_block_is_one_line_naming_the_field(campaign, verification, path, value, field):
    doc = mes_result(build(campaign, verification=verification))
    target = doc["verification"]
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    with pytest.raises(InputError) as err:
        report_data_from_result(doc, source="r.json")
    assert str(err.value).startswith(f"r.json: field '{field}'")
    doc["verification"] = "yes"
    with pytest.raises(InputError, match="r.json: field 'verification' must be an object"):
        report_data_from_result(doc, source="r.json")


def test_check_verification_refuses_an_unfinished_verification_naming_its_status(verification):
    check_verification(verification, "v.json")  # a finished one passes
    with pytest.raises(InputError, match=r"v.json: verification V-2 did not finish \(status 'failed': "
                                         r"FaultError: x\)"):
        check_verification({"campaign": "V-2", "status": "failed", "error": "FaultError: x"}, "v.json")


def test_the_page_is_well_formed_with_hostile_text(page):
    root = ET.fromstring(page.split("\n", 1)[1])
    assert root.tag == "html" and "<script>" not in page
