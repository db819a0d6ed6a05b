"""`hil verify --sim` as a process on the simulated station (real ur_rtde and GeoCOM clients, fast
time): both modes against the simulator's hidden truth, which is also the model here, so the
compensated test is limited by the tracker's and the encoders' noise only. About 30 s."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from hil.calibration.model_file import truth_document
from hil.calibration.synthetic import Noise, random_truth
from hil.store import Store
from mocks.station import simulated_serial

ROOT = Path(__file__).resolve().parents[3]


def test_verify_on_the_simulated_station_with_the_true_model(tmp_path: Path) -> None:
    truth = random_truth("ur5e", np.random.default_rng(21), rigid=True)  # cold and rigid: the model is exact
    (tmp_path / "truth.json").write_text(json.dumps(truth_document(truth, Noise())))
    (tmp_path / "model.json").write_text(json.dumps({"format": "hil-model/1", **truth.to_dict()}))
    out = tmp_path / "result.json"
    cmd = [sys.executable, "-m", "hil", "verify", "--sim", "--truth", str(tmp_path / "truth.json"),
           "--model", str(tmp_path / "model.json"), "--speed", "100", "--cycles", "2",
           "--db", str(tmp_path / "hil.db"), "--json", "--out", str(out)]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=240)
    assert done.returncode == 0, done.stderr[-3000:]
    events = [json.loads(line) for line in done.stdout.splitlines()]
    assert events[-1]["event"] == "RunFinished" and events[-1]["status"] == "accepted"
    assert sum(e["event"] == "PointMeasured" for e in events) == 2 * 5 * 2
    doc = json.loads(out.read_text())
    unc, comp = doc["results"]["uncompensated"], doc["results"]["compensated"]
    assert comp["AP_max"] < 5e-5  # 20 µm tracker noise over 5 samples, encoder noise, 2 cycles
    assert unc["AP_max"] > 5 * comp["AP_max"]
    assert doc["truth"]["format"] == "hil-truth/1" and doc["frame"]["source"] == "model"


def test_a_simulated_station_keeps_its_campaigns_apart_from_the_plants(tmp_path: Path) -> None:
    """Without --db a simulated station's verification goes to the simulated stations' store (sim.db
    beside the default), not to $HIL_DB (the plant's history, where it showed up in hil robots and the
    fleet report), and says so; its robot is the simulated arm's own serial."""
    plant, data = tmp_path / "plant.db", tmp_path / "data"
    env = {**os.environ, "HIL_DB": str(plant), "XDG_DATA_HOME": str(data)}
    cmd = [sys.executable, "-m", "hil", "verify", "--sim", "--ideal",
           "--speed", "100", "--cycles", "2", "--seed", "4"]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=240, env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    sim = data / "hil" / "sim.db"
    assert not plant.exists() and sim.exists()
    said = [line for line in done.stderr.splitlines() if line.startswith("hil: simulated station:")]
    assert len(said) == 1 and str(sim) in said[0] and "$HIL_DB" in said[0], done.stderr[-3000:]
    with Store.open(sim, readonly=True) as store:
        (campaign,) = store.campaigns()
        assert store.campaign(campaign.id).robot.serial == simulated_serial("ur5e", 4, ideal=True)
