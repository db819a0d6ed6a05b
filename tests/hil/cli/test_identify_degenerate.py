"""`hil identify` on data that cannot identify the arm exits 2 and says why (issue 19: constant x,y,z
exited 0 with a condition number of 8e15 and wrote a model)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from hil.calibration.identification import identify
from hil.calibration.measurements import Measurements, read_measurements, write_measurements
from hil.cli import main
from hil.errors import InputError


@pytest.fixture(scope="module")
def station(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("station")
    assert main(["synth", "--ideal", "--robot", "ur5e", "--poses", "30", "--validation", "10", "--seed", "11",
                 "--out-dir", str(out)]) == 0
    return out


def run_identify(capsys, measurements: Path, out: Path) -> tuple[int, str]:
    code = main(["identify", "--robot", "ur5e", "--measurements", str(measurements), "--out", str(out)])
    return code, capsys.readouterr().err.strip()


@pytest.mark.parametrize(("points", "shape"), [
    (lambda q, p: np.tile([1.0, 0.5, 0.2], (len(q), 1)), "are all the same point (rank 0 of 3"),
    (lambda q, p: np.outer(q[:, 0], [0.3, 0.1, 0.0]) + np.array([1.0, 0.0, 0.0]),
     "all lie on one line (rank 1"),
])
def test_points_that_cannot_identify_the_arm_are_refused_before_fitting(station, tmp_path, capsys,
                                                                         points, shape) -> None:
    meas = read_measurements(station / "measurements.csv")
    bad = tmp_path / "flat.csv"
    write_measurements(bad, meas.q, points(meas.q, meas.p))
    out = tmp_path / "model.json"
    code, err = run_identify(capsys, bad, out)
    assert code == 2, err
    assert err.startswith(f"hil: error: {bad}: the measured points x,y,z {shape}"), err
    assert "cannot identify" in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_a_fit_whose_jacobian_loses_rank_is_not_a_success(station, tmp_path, capsys) -> None:
    """Points on a circle that follows joint 1 alone pass the spread check but are fitted only by an
    arm whose other joints collapsed: the rank at the solution is below the 27 parameters."""
    meas = read_measurements(station / "measurements.csv")
    q1 = meas.q[:, 0]
    bad = tmp_path / "circle.csv"
    write_measurements(bad, meas.q, np.column_stack([np.cos(q1), np.sin(q1), np.zeros_like(q1)]))
    out = tmp_path / "model.json"
    with warnings.catch_warnings(record=True) as caught:  # the refusal is the only thing printed
        warnings.simplefilter("always")
        code, err = run_identify(capsys, bad, out)
    assert code == 2, err
    assert not caught, [str(w.message) for w in caught]
    assert len(err.splitlines()) == 1
    assert f"{bad}: the data cannot identify the 27 parameters: at the fitted model the Jacobian " \
           "has numerical rank" in err and "condition number" in err, err
    assert not out.exists()


def test_good_data_still_identifies(station, tmp_path, capsys) -> None:
    out = tmp_path / "model.json"
    code, err = run_identify(capsys, station / "measurements.csv", out)
    assert code == 0, err
    assert out.exists()


def test_the_library_refuses_too() -> None:
    """Callers of `identify` get the same InputError as the CLI (a ValueError, as the docs promise)."""
    rng = np.random.default_rng(3)
    q = rng.uniform(-3, 3, (30, 6))
    with pytest.raises(InputError, match="the measured points x,y,z are all the same point"):
        identify(Measurements.from_arrays(q, np.zeros((30, 3)), source="zeros"), "ur5e")
