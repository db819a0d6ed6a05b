"""`hil identify` cross-validates every fit and never hands out a model that may make the arm worse
(issue 30): the figures in the model and the JSON summary, exit 1 and one line on a hopeless data set,
and `hil export` / `hil compensate` refusing such a model (exit 2) unless `--force`."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from hil.calibration.measurements import write_measurements
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from hil.cli import main


def synthetic_csv(path: Path, poses: int, sigma: float, seed: int) -> Path:
    rng = np.random.default_rng(seed)
    truth = random_truth("ur5e", rng, rigid=True)
    q, p = measure(truth, random_configurations("ur5e", poses, rng), Noise(sigma), rng)
    write_measurements(path, q, p)
    return path


@pytest.fixture(scope="module")
def models(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    out = tmp_path_factory.mktemp("cv")
    good = synthetic_csv(out / "good.csv", 30, 20e-6, 1)
    bad = synthetic_csv(out / "bad.csv", 12, 3e-3, 1)  # a camera's noise on a dozen poses
    return {"good_csv": good, "bad_csv": bad, "dir": out}


def identify(csv: Path, out: Path, *extra: str) -> int:
    return main(["identify", "--robot", "ur5e", "--measurements", str(csv), "--out", str(out), *extra])


def test_a_good_fit_is_cross_validated_and_marked_better(models, capsys) -> None:
    out = models["dir"] / "good.json"
    assert identify(models["good_csv"], out, "--json") == 0
    summary = json.loads(capsys.readouterr().out)
    doc = json.loads(out.read_text())
    assert doc["better_than_nominal"] is True and summary["better_than_nominal"] is True
    cv = doc["cross_validation"]
    assert cv["folds"] == 10 and cv["poses"] == 30 and cv["controller"] is None
    assert cv["calibrated"]["rms"] < 0.1e-3 < 1e-3 < cv["nominal"]["rms"]
    assert summary["cross_validation"]["calibrated"] == cv["calibrated"]
    assert doc["fit"]["prior"]["translation_tolerance"] == pytest.approx(1e-3)


def test_a_hopeless_data_set_exits_1_says_so_and_is_marked(models, capsys) -> None:
    out = models["dir"] / "bad.json"
    assert identify(models["bad_csv"], out) == 1
    captured = capsys.readouterr()
    err = [line for line in captured.err.splitlines() if line.startswith("hil:")]
    assert len(err) == 1 and "does not predict held-out poses better than the nominal model" in err[0]
    assert "NOT BETTER" in captured.out
    doc = json.loads(out.read_text())  # written, so it can be looked at
    assert doc["better_than_nominal"] is False and doc["cross_validation"]["better_than_nominal"] is False


@pytest.mark.parametrize("fmt", ["urdf", "ros-kinematics", "json"])
def test_export_refuses_a_model_not_better_than_nominal_unless_forced(models, capsys, fmt) -> None:
    model = models["dir"] / "bad.json"
    if not model.exists():
        assert identify(models["bad_csv"], model) == 1
    target = models["dir"] / f"exported-{fmt}.out"
    capsys.readouterr()
    assert main(["export", "--model", str(model), "--format", fmt, "--out", str(target)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "better_than_nominal is false" in err and "--force" in err
    assert not target.exists()
    assert main(["export", "--model", str(model), "--format", fmt, "--out", str(target), "--force"]) == 0
    assert target.exists() and "exported anyway (--force)" in capsys.readouterr().err


def test_compensate_refuses_it_too(models, capsys, tmp_path) -> None:
    model = models["dir"] / "bad.json"
    if not model.exists():
        assert identify(models["bad_csv"], model) == 1
    controller = tmp_path / "controller.json"
    controller.write_text(json.dumps({"robot": "ur5e", "controller": {
        k: [0.0] * 6 for k in ("delta_theta", "delta_a", "delta_d", "delta_alpha")}}))
    poses = tmp_path / "poses.csv"
    poses.write_text("x,y,z,rx,ry,rz\n0.4,0.1,0.3,3.14,0,0\n")
    out = tmp_path / "out.csv"
    capsys.readouterr()
    argv = ["compensate", str(poses), "--model", str(model), "--controller", str(controller),
            "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "better_than_nominal is false" in err and not out.exists()
    assert main([*argv, "--force"]) == 0 and out.exists()


def test_the_controller_model_is_cross_validated_beside(models, capsys, tmp_path) -> None:
    """--controller: its held-out figures join the model; a controller as good as nominal is beaten."""
    controller = tmp_path / "controller.json"
    controller.write_text(json.dumps({"robot": "ur5e", "controller": {
        k: [0.0] * 6 for k in ("delta_theta", "delta_a", "delta_d", "delta_alpha")}}))
    out = tmp_path / "model.json"
    assert identify(models["good_csv"], out, "--controller", str(controller)) == 0
    cv = json.loads(out.read_text())["cross_validation"]
    assert cv["controller"]["rms"] == pytest.approx(cv["nominal"]["rms"], rel=1e-3)
    assert cv["better_than_controller"] is True
