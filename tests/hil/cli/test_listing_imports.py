"""The listing commands (``hil history``, ``hil show``, ``hil robots``, ``hil robot``) read the store
and print: they import none of the numerical libraries, no schema-migration tool and no robot driver,
which were nearly all of their 3 s of start-up (a test of modules, not of time: the time is measured
by ``bench/cli_startup.py``)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from hil.arm.geometry import Geometry
from hil.calibration.exports import FORMATS
from hil.calibration.model_file import MODEL_FORMAT
from hil.campaign.events import ModelIdentified, PointMeasured, RunFinished, RunStarted, ValidationDone
from hil.cli.support import export_formats
from hil.station.config import default_config
from hil.store import RobotIdentity, Store

ROOT = Path(__file__).resolve().parents[3]
SERIAL = "20235500101"
#: what a listing must not import: the numerical stack, SQLAlchemy (a station's SQLite file at the head
#: revision is read with sqlite3: hil.store.sqlite_reader), Alembic (a store at the head revision needs no
#: migration), the robot driver (ur_rtde's client) and the campaign's event types
HEAVY = ("numpy", "scipy", "pinocchio", "matplotlib", "sqlalchemy", "alembic", "drivers.robot.ur",
         "hil.campaign.events")


@pytest.fixture(scope="module")
def db(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A store with one accepted calibration of robot `SERIAL`, model and validation included."""
    path = tmp_path_factory.mktemp("listing") / "hil.db"
    model = {"format": MODEL_FORMAT, **Geometry.nominal("ur5e").to_dict(),
             "parameters": [{"name": "p", "value": 0.0, "std": 1e-6}] * 27,
             "fit": {"rms": 18e-6, "max": 45e-6, "iterations": 6, "rejected": []},
             "input": {"file": "campaign", "sha256": "0" * 64}}
    with Store.open(path) as s:
        cid = s.create_campaign(default_config().as_dict(), RobotIdentity("ur5e", SERIAL, "UR5e", "5.15"),
                                now=1.7e9)
        s.save_plan(cid, [(i, "calibration" if i < 3 else "validation", [0.1 * i] * 6) for i in range(5)])
        s.record_event(RunStarted(campaign=cid, robot="ur5e", station="cell", poses=5))
        for i in range(5):
            s.record_event(PointMeasured(campaign=cid, index=i, role="calibration" if i < 3 else "validation",
                                         q=[0.1 * i] * 6, p=[1.0, 2.0, i], p_spread=[0] * 3, samples=5))
        s.record_event(ModelIdentified(campaign=cid, rms=18e-6, max=45e-6, iterations=6, rejected=[],
                                       model=model))
        s.record_event(ValidationDone(campaign=cid, before={"count": 2, "rms": 1.8e-3, "max": 2e-3},
                                      after={"count": 2, "rms": 21e-6, "max": 40e-6}, passed=True))
        s.record_event(RunFinished(campaign=cid, status="accepted"))
    return path


def loaded_by(argv: list[str], modules: tuple[str, ...] = HEAVY) -> tuple[int, list[str]]:
    """(exit code, the `modules` loaded) after `hil ARGV` in a fresh interpreter."""
    code = ("import contextlib, io, sys\n"
            "from hil.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):\n"
            f"    rc = main({argv!r})\n"
            f"print(rc, ','.join(m for m in {modules!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    rc, _, loaded = out.stdout.strip().partition(" ")
    return int(rc), [m for m in loaded.split(",") if m]


@pytest.mark.parametrize("argv", [["history"], ["history", "--json"], ["show", "last"], ["robots"],
                                  ["robot", SERIAL]], ids=" ".join)
def test_a_listing_imports_nothing_heavy(db: Path, argv: list[str]) -> None:
    assert loaded_by([*argv, "--db", str(db)]) == (0, [])


def test_the_export_formats_a_listing_offers_are_the_exporters(db: Path) -> None:
    assert export_formats.FORMATS == FORMATS
    assert {export_formats.format_of(f"m{s}") for s in (".urdf", ".XML", ".yaml", ".yml", ".json", "")} \
        == set(FORMATS)
    assert export_formats.format_of("m.urdf", "json") == "json"


def test_identify_imports_neither_the_store_nor_scipy_nor_numpy_ma(tmp_path: Path) -> None:
    """``hil identify`` checks its output against the store's path without opening (or importing) the
    store, and on data without outliers it loads no scipy at all: the pivoted QR and the Kabsch fit are
    numpy's, and the outlier test's F distribution is imported only when a pose may be an outlier.
    scipy's import (its linalg, special and spatial parts) was 0.35 s of the 0.75 s it took. Nor
    numpy.ma, which numpy 2.4's ``np.unique`` imports (a tenth of the fit's time). Nor the trackers'
    protocol clients (the polar convention is all it needs of `drivers.tracker`) nor the station's
    configuration reader (its --smr bound is a row of `hil.files.quantities`): a fifth of its start-up."""
    import numpy as np

    from hil.calibration.measurements import write_measurements
    from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth

    rng = np.random.default_rng(3)
    q, p = measure(random_truth("ur5e", rng), random_configurations("ur5e", 40, rng), Noise(), rng)
    write_measurements(tmp_path / "m.csv", q, p)
    code = ("import contextlib, io, sys\n"
            "from hil.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):\n"
            f"    rc = main(['identify', '--robot', 'ur5e', '--measurements', {str(tmp_path / 'm.csv')!r}, "
            f"'--out', {str(tmp_path / 'model.json')!r}])\n"
            "print(rc, ','.join(m for m in ('sqlalchemy', 'scipy', 'numpy.ma', 'drivers.tracker.emscon', "
            "'drivers.tracker.geocom', 'hil.station.config') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300,
                         env={**os.environ, "XDG_DATA_HOME": str(tmp_path / "data")})
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["0"], out.stdout
    assert (tmp_path / "model.json").exists()


def test_a_listings_help_does_not_import_the_store() -> None:
    assert loaded_by(["history", "--help"], (*HEAVY, "sqlalchemy")) == (0, [])


def test_a_listing_does_not_look_up_hils_version(db: Path) -> None:
    """Reading hil's package metadata is for what records the version (a new campaign, a model file),
    not for a listing."""
    code = ("import contextlib, io, sys\n"
            "from hil.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):\n"
            f"    rc = main(['history', '--db', {str(db)!r}])\n"
            "print(rc, '__version__' in vars(sys.modules['hil']))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["0", "False"]
