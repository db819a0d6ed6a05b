"""A controller of another robot is refused by ``hil calibrate``, ``hil verify`` and ``hil moveb run``
before they load what only a run needs (issue 31: every refusal within 2 s; cold, these imports were
most of it): the MOVEB planner (SciPy's splines), the verification runner, the campaign engine and
SQLAlchemy. A test of modules in a fresh interpreter, not of time (the time:
``bench/adversarial.py --station``), against a simulated UR5e whose configuration says ur10e.
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "hil" / "moveb" / "examples"
#: what only a run needs, imported once the station is taken
RUN_ONLY = ("scipy.interpolate", "scipy.linalg", "sqlalchemy", "hil.campaign.engine", "hil.campaign.runner",
            "hil.verify.session", "hil.moveb.path_plan", "hil.moveb.run")


@pytest.fixture(scope="module")
def station() -> Iterator[Any]:
    from mocks.station import start_station

    sim = start_station(robot="ur5e", speed=20.0, seed=3, ideal=True)
    try:
        yield sim
    finally:
        sim.stop()


def _config(sim: Any, path: Path) -> Path:
    path.write_text(f'[robot]\ntype = "ur10e"\naddress = "{sim.address}"\n'
                    f'[tracker]\nurl = "{sim.info["services"][0]["tracker_url"]}"\n'
                    "[keep_in]\nmin = [-2.0, -2.0, 0.0]\nmax = [2.0, 2.0, 2.0]\n"
                    "[verify]\ncentre = [0.5, 0.0, 0.3]\nedge = 0.2\n")
    return path


def refused(argv: list[str], cwd: Path) -> tuple[int, str, list[str]]:
    """(exit code, stderr, the `RUN_ONLY` modules loaded) after `hil ARGV` in a fresh interpreter."""
    code = ("import contextlib, io, json, sys\n"
            "from hil.cli import main\n"
            "err = io.StringIO()\n"
            "with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):\n"
            f"    rc = main({argv!r})\n"
            f"print(json.dumps([rc, err.getvalue(), [m for m in {RUN_ONLY!r} if m in sys.modules]]))")
    out = subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True, timeout=120,
                         env={**_env(), "PYTHONPATH": str(ROOT)})
    assert out.returncode == 0, out.stderr
    rc, err, loaded = json.loads(out.stdout.strip().splitlines()[-1])
    return rc, err, loaded


def _env() -> dict[str, str]:
    import os

    return {k: v for k, v in os.environ.items() if k != "HIL_DB"}


@pytest.mark.parametrize("command", ["calibrate", "verify", "moveb run"])
def test_a_controller_of_another_robot_is_refused_without_the_runs_modules(
        station: Any, tmp_path: Path, command: str) -> None:
    config = _config(station, tmp_path / "station.toml")
    argv = {"calibrate": ["calibrate", "--config", str(config), "--db", str(tmp_path / "k.db"),
                          "--poses", "12", "--validation", "4"],
            "verify": ["verify", "--config", str(config), "--db", str(tmp_path / "k.db")],
            "moveb run": ["moveb", "run", str(EXAMPLES / "square.moveb"), "--config", str(config),
                          "--frame", "base"]}[command]
    before = station.state()
    rc, err, loaded = refused(argv, tmp_path)
    assert rc == 2, err
    assert err == (f"hil: error: robot.type is ur10e in {config} but the controller at {station.address} "
                   "reports UR5e\n")
    assert loaded == []
    after = station.state()
    assert after["programs_received"] == before["programs_received"]  # no control script uploaded
    assert after["q"] == before["q"] and not after["moving"]
    assert not (tmp_path / "k.db").exists()
