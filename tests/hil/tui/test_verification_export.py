"""The Results screen's HTML export of a stored verification writes the pose test's own report (the page
``hil verify --report`` writes), not a calibration report it has no model for."""

from __future__ import annotations

import json

from hil.store import CampaignRecord, RobotIdentity
from hil.tui.messages import Exported
from hil.tui.session import Session, TuiOptions
from tests.hil.cli.test_verify import Station
from tests.hil.tui.test_second_round import verification_record


def test_the_html_export_of_a_verification_is_its_pose_test_report(tmp_path, monkeypatch):
    st = Station(tmp_path, monkeypatch, kinematics=True)
    assert st.verify() == 0
    doc = json.loads(st.out.read_text())
    canned = verification_record()
    record = CampaignRecord(summary=canned.summary, robot=RobotIdentity("ur5e", "20235500001"),
                            config=canned.config, config_hash=canned.config_hash, plan=canned.plan,
                            detail="", result=doc, software="0.1.0")
    posted = []
    session = Session(TuiOptions(out_dir=str(tmp_path / "exports"), start_station=False), posted.append)
    session.export(record, ["report"])
    (message,) = posted
    assert isinstance(message, Exported) and not message.error, message
    (path,) = message.paths
    page = (tmp_path / "exports" / f"{record.id}-report.html").read_text()
    assert path.endswith("-report.html") and "ISO 9283" in page
    assert "hil-result/1" not in page
