"""`hil report` of a verification (the page `hil verify --report` writes), and `hil calibrate --verify
--report` with the pose test's section, end to end on the engine's fake arm and tracker
(tests/hil/cli/test_verify.py's station); a result without figures or a malformed one is refused in
one line."""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET

from hil.cli import main
from hil.report.render import fmt_mm
from tests.hil.cli.test_verify import Station, one_line_error

GENERATED = re.compile(r'<p class="generated">Generated [^<]*</p>')


def sections(page: str) -> dict[str, ET.Element]:
    root = ET.fromstring(page.split("\n", 1)[1])
    return {s.get("id"): s for s in root.iter("section")}


def table_rows(section: ET.Element) -> list[list[list[str]]]:
    return [[["".join(td.itertext()) for td in tr] for tr in t.find("tbody")] for t in section.iter("table")]


def ap_rows(block: dict) -> list[list[str]]:
    return [[p["pose"], str(p["n"])] + [fmt_mm(p[k]) for k in ("AP_x", "AP_y", "AP_z", "AP_P", "S_l", "RP_l")]
            for p in block["poses"]]


def test_hil_report_of_a_verification_result_is_the_page_hil_verify_wrote(tmp_path, monkeypatch, capsys):
    st = Station(tmp_path, monkeypatch, kinematics=True)
    assert st.verify("--report", str(st.report)) == 0
    err = capsys.readouterr().err
    # the progress says what a verification does: visits of P1-P5, the mode, the cycle
    assert re.search(r"starting verification \S+ on ur5e \(cell-9\), 30 visits planned \(poses P1–P5, 3 "
                     r"cycles, uncompensated and compensated\)", err), err
    assert "measured visit 1 (P1 uncompensated, cycle 1 of 3), " in err and " mm from commanded" in err
    assert "measured visit 30 (P2 compensated, cycle 3 of 3)" in err
    assert re.search(r"verification \S+ finished: ISO 9283 over 3 cycles", err)
    assert "calibration + validation" not in err and "from nominal" not in err
    again = tmp_path / "again.html"
    assert main(["report", "--result", str(st.out), "--out", str(again)]) == 0
    assert f"wrote {again} (ISO 9283 pose test)" in capsys.readouterr().err
    first, second = st.report.read_text(), again.read_text()
    assert GENERATED.sub("", first) == GENERATED.sub("", second)  # the same page but its timestamp
    doc = json.loads(st.out.read_text())
    rows = table_rows(sections(second)["results"])
    assert rows[0] == ap_rows(doc["results"]["uncompensated"])
    assert rows[1] == ap_rows(doc["results"]["compensated"])


def test_calibrate_verify_report_has_the_pose_test_and_hil_report_rebuilds_it(tmp_path, monkeypatch, capsys):
    st = Station(tmp_path, monkeypatch, kinematics=True)
    tracker = ", ".join(map(str, st.truth.tracker.translation + 0.05))
    smr = ", ".join(map(str, st.truth.smr + 0.003))
    st.config.write_text(st.config.read_text().replace('url = "/dev/ttyFAKE"\n',
                                                       f'url = "/dev/ttyFAKE"\nposition = [{tracker}]\n')
                         + f"[smr]\noffset = [{smr}]\n")
    code = main(["calibrate", "--config", str(st.config), "--db", str(st.db), "--poses", "14", "--validation",
                 "4", "--out", str(st.out), "--report", str(st.report), "--verify", "--verify-cycles", "2"])
    err = capsys.readouterr().err
    assert code == 0, err
    # each run's progress in its own words: the calibration's poses, then the verification's visits
    assert re.search(r"starting campaign \S+ on ur5e \(cell-9\), 18 poses planned \(calibration \+ "
                     r"validation\)", err)
    assert "20 visits planned (poses P1–P5, 2 cycles, uncompensated and compensated)" in err
    assert "measured visit 20 (P2 compensated, cycle 2 of 2)" in err
    doc = json.loads(st.out.read_text())
    v = doc["verification"]
    page = st.report.read_text()
    sec = sections(page)["verification"]
    rows = table_rows(sec)
    assert rows[0] == ap_rows(v["results"]["uncompensated"])
    assert rows[1] == ap_rows(v["results"]["compensated"])
    assert f"verification campaign {v['campaign']}" in "".join(sec.itertext())
    assert len(sec.findall("figure")) == 1
    for mode, block in v["results"].items():
        assert f"Pose test AP {mode}" in page and fmt_mm(block["AP_max"]) in page
    rebuilt = tmp_path / "rebuilt.html"
    assert main(["report", "--result", str(st.out), "--out", str(rebuilt)]) == 0
    assert table_rows(sections(rebuilt.read_text())["verification"]) == rows


def test_a_verification_result_without_figures_or_malformed_is_refused_in_one_line(tmp_path, capsys):
    result, out = tmp_path / "v.json", tmp_path / "r.html"
    result.write_text(json.dumps({"format": "hil-verification/1", "campaign": "20260101-000000-abcd",
                                  "status": "interrupted", "exit_code": 130, "error": "RunInterrupted: x"}))
    assert main(["report", "--result", str(result), "--out", str(out)]) == 2
    err = one_line_error(capsys)
    assert str(result) in err and "did not finish" in err and "'interrupted'" in err
    result.write_text(json.dumps({"format": "hil-verification/1", "results": {"compensated": {
        "AP_max": 1e-5, "RP_max": 1e-5, "poses": [{"pose": "P1", "AP_P": 1e-5}]}}}))
    assert main(["report", "--result", str(result), "--out", str(out)]) == 2
    assert "field 'results.compensated.poses[0].n'" in one_line_error(capsys)
    good = {"pose": "P1", "n": 2, "AP_x": 0, "AP_y": 0, "AP_z": 0, "AP_P": 0, "S_l": 0, "RP_l": 0,
            "offsets": [[0, 0, 0], [0, 0, 0]]}
    result.write_text(json.dumps({"format": "hil-verification/1", "cube": [1, 2], "results": {
        "compensated": {"AP_max": 0, "RP_max": 0, "poses": [good]}}}))
    assert main(["report", "--result", str(result), "--out", str(out)]) == 2
    assert f"{result}: malformed result" in one_line_error(capsys)
    assert not out.exists()
