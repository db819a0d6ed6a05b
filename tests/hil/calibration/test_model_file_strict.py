"""Model and truth JSON hold real, finite, physically plausible numbers, or are refused naming the field
path (issue 19: `true`, "1" and 1e308 geometry used to load and drive the arm or the planner)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from hil.calibration.model_file import load_geometry, load_truth
from hil.cli import main


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("station")
    assert main(["synth", "--robot", "ur5e", "--poses", "30", "--validation", "10", "--seed", "7",
                 "--out-dir", str(out)]) == 0
    assert main(["identify", "--robot", "ur5e", "--measurements", str(out / "measurements.csv"),
                 "--out", str(out / "model.json")]) == 0
    return out


def edited(src: Path, dst: Path, change: Callable[[dict[str, Any]], None]) -> Path:
    doc = json.loads(src.read_text())
    change(doc)
    dst.write_text(json.dumps(doc))
    return dst


def setter(*path: Any) -> Callable[[Any], Callable[[dict[str, Any]], None]]:
    """A change that sets the item at `path` (keys and indices) to a value."""
    def with_value(value: Any) -> Callable[[dict[str, Any]], None]:
        def change(doc: dict[str, Any]) -> None:
            node = doc
            for key in path[:-1]:
                node = node[key]
            node[path[-1]] = value
        return change
    return with_value


BAD = [
    (setter("joints", 2, "xyz", 0)(True), "joints[2].xyz[0]: expected a number, got true"),
    (setter("joints", 2, "xyz", 0)("1"), 'joints[2].xyz[0]: expected a number, got "1"'),
    (setter("joints", 0, "rpy", 1)(None), "joints[0].rpy[1]: expected a number, got null"),
    (setter("joints", 4, "xyz", 2)(1e308),
     "joints[4].xyz[2]: must be in [-1.5, 1.5] m, got 1e+308"),
    (setter("flange", "rpy", 0)(100.0),
     "flange.rpy[0]: must be in [-6.28319, 6.28319] rad, got 100; 100 looks like degrees"),
    (setter("flange", "xyz", 1)(float("nan")),
     "flange.xyz[1]: expected a finite number in [-1.5, 1.5] m, got nan"),
    (setter("smr", 2)(10.0), "smr[2]: must be in [-1, 1] m, got 10"),
    (setter("tracker", "xyz", 0)(-500.0), "tracker.xyz[0]: must be in [-80, 80] m, got -500"),
    (setter("tracker", "rpy", 2)(float("inf")),
     "tracker.rpy[2]: expected a finite number in [-6.28319, 6.28319] rad, got inf"),
    (setter("robot")("ur99"), "robot: unknown robot 'ur99': choose one of"),
]


@pytest.mark.parametrize(("change", "says"), BAD)
def test_fk_refuses_a_model_with_a_bad_number_naming_the_field(files, tmp_path, capsys, change,
                                                               says) -> None:
    bad = edited(files / "model.json", tmp_path / "model.json", change)
    out = tmp_path / "p.csv"
    code = main(["fk", "--model", str(bad), "--joints", str(files / "measurements.csv"), "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert err == f"hil: error: {bad}: {says}" or err.startswith(f"hil: error: {bad}: {says}"), err
    assert len(err.splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize(("change", "says"), BAD[:3])
def test_synth_refuses_a_truth_with_a_bad_number(files, tmp_path, capsys, change, says) -> None:
    bad = edited(files / "truth.json", tmp_path / "truth.json", change)
    code = main(["synth", "--truth", str(bad), "--out-dir", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and f"{bad}: {says}" in err, err
    assert not (tmp_path / "out" / "measurements.csv").exists()


@pytest.mark.parametrize(("key", "value", "says"), [
    ("tracker_sigma", True, "noise.tracker_sigma: expected a number, got true"),
    ("encoder_sigma", "0", 'noise.encoder_sigma: expected a number, got "0"'),
    ("tracker_sigma", 5.0, "noise.tracker_sigma: must be in [0, 0.01] m, got 5"),
    ("encoder_sigma", -1e-6, "noise.encoder_sigma: must be in [0, 0.01] rad, got -1e-06"),
    ("standstill_sigma", 0.5, "noise.standstill_sigma: must be in [0, 0.01] rad, got 0.5"),
])
def test_a_truth_s_noise_must_be_a_plausible_number(files, tmp_path, key, value, says) -> None:
    bad = edited(files / "truth.json", tmp_path / "truth.json", setter("noise", key)(value))
    with pytest.raises(ValueError, match=r"^" + str(bad).replace(".", r"\.") + ": ") as info:
        load_truth(bad)
    assert str(info.value).startswith(f"{bad}: {says}")


def test_a_campaign_result_names_the_field_under_model(files, tmp_path) -> None:
    model = json.loads((files / "model.json").read_text())
    model["smr"][0] = True
    result = tmp_path / "result.json"
    result.write_text(json.dumps({"format": "hil-result/1", "status": "accepted", "model": model}))
    with pytest.raises(ValueError, match=r"result\.json: model\.smr\[0\]: expected a number, got true$"):
        load_geometry(result)


def test_the_files_hil_writes_still_load(files) -> None:
    """The checks reject nothing hil itself writes: the identified model and the random truth."""
    geometry, doc = load_geometry(files / "model.json")
    assert doc["format"] == "hil-model/1" and geometry.robot == "ur5e"
    truth, noise = load_truth(files / "truth.json")
    assert truth.robot == "ur5e" and noise.tracker_sigma is None and noise.distance_sigma > 0
