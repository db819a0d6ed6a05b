"""`hil verify --sim` as a process on the simulated station (real ur_rtde and GeoCOM clients, fast
time): both modes against the simulator's hidden truth, which is also the model here, so the
compensated test is limited by the tracker's and the encoders' noise only. About 30 s."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from hil.calibration.model_file import truth_document
from hil.calibration.synthetic import Noise, random_truth

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
