"""`hil verify` (and `hil calibrate --verify`) end to end on the engine's fake arm and tracker
(tests/hil/campaign/fakes.py), in this process: both modes against a hidden truth, the result, the
report and the store; an interrupted test resuming without measuring twice; bad input refused in one
line before anything connects."""

from __future__ import annotations

import json
import signal
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from hil.arm.controller_model import ControllerCalibration
from hil.calibration.synthetic import random_truth
from hil.campaign.calibration_plan import Choice
from hil.cli import main
from hil.store import Store
from hil.verify.cube import CYCLE_ORDER, POSE_NAMES
from hil.verify.design import default_cube
from mocks.world import World
from tests.hil.campaign.fakes import FakeArm, FakeTracker, visible_poses


class Devices:
    def __init__(self, arm: FakeArm, tracker: FakeTracker) -> None:
        self.robot, self.tracker = arm, tracker
        self.closed = 0

    def close(self) -> None:
        self.closed += 1


class Station:
    """One fake cell shared by successive commands (same arm, same store)."""

    def __init__(self, tmp_path: Path, monkeypatch, *, kinematics: bool = False, centre: bool = True) -> None:
        rng = np.random.default_rng(4)
        self.truth = random_truth("ur5e", rng, rigid=True)  # verifying, not modelling the sag
        self.arm = FakeArm(World(self.truth, lambda: np.zeros(6)).home_pose(rng))
        deltas = ControllerCalibration(rng.normal(0, 1e-3, 6), rng.normal(0, 3e-4, 6), rng.normal(0, 3e-4, 6),
                                       rng.normal(0, 1e-3, 6))
        theta, a, d, alpha = deltas.dh("ur5e")
        reported = {"checksum": deltas.checksums(), "dh_theta": list(theta), "dh_a": list(a),
                    "dh_d": list(d), "dh_alpha": list(alpha), "calibration_status": 1}
        self.arm.info = SimpleNamespace(serial="20235500042", model="UR5e", software_version="5.15",
                                        kinematics=reported if kinematics else None)
        self.tracker = FakeTracker(self.arm, self.truth, sigma=5e-6)
        self.opened: list[Devices] = []
        self.signal_after: int | None = None
        move = self.arm.move_to

        def move_to(q, **kw):
            if self.signal_after is not None and self.tracker.measurements == self.signal_after:
                self.signal_after = None
                signal.raise_signal(signal.SIGINT)  # Ctrl-C while the arm moves
            return move(q, **kw)

        self.arm.move_to = move_to
        cube = default_cube("ur5e", self.truth.tracker.translation)
        verify = (f"[verify]\ncentre = [{', '.join(map(str, cube.centre))}]\nedge = {cube.edge}\n"
                  if centre else "")
        self.config = tmp_path / "station.toml"
        self.config.write_text('[station]\nname = "cell-9"\n[robot]\nsettle_time = 0.0\njoint_samples = 2\n'
                               '[tracker]\nurl = "/dev/ttyFAKE"\n'
                               "[keep_in]\nmin = [-2.0, -2.0, 0.0]\nmax = [2.0, 2.0, 2.0]\n"
                               "[campaign]\nsamples = 2\nacceptance = 0.01\n"
                               "[warmup]\nenabled = false\n[drift]\nevery = 0\n" + verify)  # wall clock
        self.model = tmp_path / "model.json"
        self.model.write_text(json.dumps({"format": "hil-model/1", **self.truth.to_dict()}))
        self.db, self.out, self.report = tmp_path / "hil.db", tmp_path / "result.json", tmp_path / "r.html"

        def open_devices(config):
            self.opened.append(Devices(self.arm, self.tracker))
            return self.opened[-1]

        def chooser(config):  # calibrate --verify: random visible poses, the selector is not tested here
            def choose(request):
                return Choice(visible_poses(request.model, request.count, rng), {"method": "test"})

            return choose

        monkeypatch.setattr("hil.station.devices.open_devices", open_devices)
        monkeypatch.setattr("hil.station.devices.ask_controller", lambda config: self.arm.info)
        monkeypatch.setattr("hil.campaign.chooser.campaign_chooser", chooser)

    def verify(self, *extra: str, model: bool = True) -> int:
        return main(["verify", "--config", str(self.config), "--db", str(self.db), "--cycles", "3",
                     "--out", str(self.out), *(["--model", str(self.model)] if model else []), *extra])

    def measured(self) -> Counter:
        with Store.open(self.db) as store:
            return Counter(m.index for c in store.campaigns() for m in store.measurements(c.id))


def test_the_true_model_compensates_what_the_controllers_own_model_misses(tmp_path, monkeypatch, capsys):
    st = Station(tmp_path, monkeypatch, kinematics=True)
    assert st.verify("--report", str(st.report)) == 0, capsys.readouterr().err
    doc = json.loads(st.out.read_text())
    assert doc["format"] == "hil-verification/1" and doc["status"] == "accepted" and doc["exit_code"] == 0
    unc, comp = doc["results"]["uncompensated"], doc["results"]["compensated"]
    assert [p["pose"] for p in unc["poses"]] == list(POSE_NAMES) and {p["n"] for p in comp["poses"]} == {3}
    assert comp["AP_max"] < 2e-5 and unc["AP_max"] > 2e-4 and unc["AP_max"] > 10 * comp["AP_max"]
    for row in comp["poses"]:
        assert {"AP_x", "AP_y", "AP_z", "AP_P", "l_mean", "S_l", "RP_l"} <= set(row)
        assert row["RP_l"] < 5e-5  # the fake tracker's 5 µm noise, averaged over 2 samples
    assert doc["orientation"] == "not measured: one SMR gives position only"
    assert doc["frame"]["source"] == "model" and doc["compensated"] is True
    assert doc["controller"]["reported"] is True and doc["controller"]["calibration_status"] == 1
    assert doc["model"]["sha256"] and doc["cycles"] == 3 and doc["cycle_order"] == list(CYCLE_ORDER)
    # the report: one well-formed page, the table and the figure of both modes
    html = st.report.read_text()
    ET.fromstring(html.split("\n", 1)[1])
    assert "ISO 9283 pose test" in html and html.count("<table") >= 3 and "data:image/png;base64," in html
    # stored like a campaign: `hil history` lists it; its plan says what it is
    with Store.open(st.db) as store:
        (summary,) = store.campaigns()
        record = store.campaign(summary.id)
    assert summary.status == "accepted" and record.plan["kind"] == "verification"
    assert len(record.poses) == 30 and all(p.status == "measured" for p in record.poses)
    assert record.result["results"]["compensated"]["AP_max"] == comp["AP_max"]
    assert main(["history", "--db", str(st.db)]) == 0 and summary.id in capsys.readouterr().out
    # the arm: a lead-in to P2 (the last mode's), then the 30 visits, nothing else
    assert len(st.arm.targets) == 31 and st.opened[-1].closed >= 1


def test_ctrl_c_leaves_it_resumable_and_the_same_command_measures_only_the_rest(tmp_path, monkeypatch,
                                                                                 capsys):
    st = Station(tmp_path, monkeypatch)
    st.signal_after = 7
    assert st.verify() == 130
    err = capsys.readouterr().err
    assert "Traceback" not in err and "resumable" in err and not st.out.exists()
    assert st.arm.stops >= 1 and sorted(st.measured()) == list(range(1, 8))
    with Store.open(st.db) as store:
        assert store.campaigns()[0].status == "interrupted"
    moves = len(st.arm.targets)
    seventh = st.arm.targets[7]  # the lead-in, then visits 1..7
    assert st.verify() == 0
    assert "resuming verification" in capsys.readouterr().err
    counts = st.measured()
    assert sorted(counts) == list(range(1, 31)) and max(counts.values()) == 1  # nothing measured twice
    assert np.allclose(st.arm.targets[moves], seventh)  # approached from visit 7's target again
    doc = json.loads(st.out.read_text())
    assert doc["measured"] == 30 and doc["status"] == "accepted"


def test_without_a_model_only_the_uncompensated_test_in_a_fitted_frame(tmp_path, monkeypatch, capsys):
    st = Station(tmp_path, monkeypatch)
    assert st.verify(model=False) == 0, capsys.readouterr().err
    doc = json.loads(st.out.read_text())
    assert list(doc["results"]) == ["uncompensated"] and doc["compensated"] is False
    assert doc["frame"]["source"] == "registered" and "lower bound" in doc["frame"]["note"]
    assert doc["controller"]["reported"] is False  # nominal DH assumed, and said so
    assert doc["tool"]["faces"]["from"] == "start pose"


def test_the_start_of_a_verification_is_said_once(tmp_path, monkeypatch, capsys):
    """The progress says "starting verification …" (with its visits, cycles and modes); the job said
    it again. Without --model the job says only why the test is uncompensated."""
    st = Station(tmp_path, monkeypatch)
    assert st.verify(model=False) == 0
    lines = capsys.readouterr().err.splitlines()
    started = [line for line in lines if "starting verification" in line]
    assert len(started) == 1 and started[0].endswith("cycles, uncompensated)"), lines
    assert sum("no --model" in line for line in lines) == 1, lines


def test_calibrate_verify_embeds_the_verification_of_the_new_model(tmp_path, monkeypatch, capsys):
    st = Station(tmp_path, monkeypatch, kinematics=True)
    tracker = ", ".join(map(str, st.truth.tracker.translation + 0.05))
    smr = ", ".join(map(str, st.truth.smr + 0.003))
    st.config.write_text(st.config.read_text().replace('url = "/dev/ttyFAKE"\n',
                                                       f'url = "/dev/ttyFAKE"\nposition = [{tracker}]\n')
                         + f"[smr]\noffset = [{smr}]\n")
    code = main(["calibrate", "--config", str(st.config), "--db", str(st.db), "--poses", "14", "--validation",
                 "4", "--out", str(st.out), "--verify", "--verify-cycles", "2"])
    assert code == 0, capsys.readouterr().err
    doc = json.loads(st.out.read_text())
    v = doc["verification"]
    assert v["format"] == "hil-verification/1" and v["status"] == "accepted" and v["cycles"] == 2
    assert v["model"]["source"] == f"campaign {doc['campaign']}"
    assert v["results"]["compensated"]["AP_max"] < v["results"]["uncompensated"]["AP_max"] / 3
    with Store.open(st.db) as store:
        kinds = sorted((store.campaign(c.id).plan or {}).get("kind", "calibration")
                       for c in store.campaigns())
        stored = store.campaign(doc["campaign"]).result
    assert kinds == ["calibration", "verification"] and stored["verification"]["campaign"] == v["campaign"]


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    return err


def test_bad_input_is_one_line_before_anything_connects(tmp_path, monkeypatch, capsys):
    st = Station(tmp_path, monkeypatch)
    base = ["verify", "--config", str(st.config), "--db", str(st.db)]
    assert main([*base, "--model", str(tmp_path / "no.json")]) == 2
    assert "no.json" in one_line_error(capsys)
    far = tmp_path / "far.toml"
    far.write_text(st.config.read_text().split("[verify]")[0] + "[verify]\ncentre = [1.4, 0.0, 0.3]\n")
    assert main(["verify", "--config", str(far), "--db", str(st.db)]) == 2
    err = one_line_error(capsys)
    assert "far.toml: verify.centre" in err and "reach" in err
    bare = tmp_path / "bare.toml"
    bare.write_text(st.config.read_text().split("[verify]")[0])
    assert main(["verify", "--config", str(bare), "--db", str(st.db)]) == 2
    assert "verify.centre" in one_line_error(capsys)
    other = tmp_path / "ur10e.json"
    other.write_text(json.dumps({"format": "hil-model/1", **random_truth("ur10e", np.random.default_rng(1),
                                                                              ideal=True)
                                 .to_dict()}))
    assert main([*base, "--model", str(other)]) == 2
    err = one_line_error(capsys)
    assert "ur10e" in err and "ur5e" in err
    assert main([*base, "--cycles", "1"]) == 2
    assert "--cycles" in one_line_error(capsys)
    assert st.opened == [] and not st.db.exists()  # nothing connected, no store created
