"""``campaign.mode`` and ``hil calibrate --mode``: validated like every key, and a sweep with a tracker
that cannot stream (GeoCOM) refused in one line, exit 2, before anything connects or a store exists."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from hil.errors import InputError
from hil.station.config import parse_config

ROOT = Path(__file__).resolve().parents[3]


def test_a_bad_mode_names_its_key():
    with pytest.raises(InputError, match=r"station.toml: campaign.mode: must be one of stop-and-go, sweep, "
                                         r"got 'swept'"):
        parse_config({"campaign": {"mode": "swept"}}, "station.toml")


def test_a_configured_sweep_with_geocom_is_refused_naming_the_key():
    with pytest.raises(InputError, match=r"campaign.mode: GeoCOM cannot stream fast enough"):
        parse_config({"campaign": {"mode": "sweep"}, "tracker": {"protocol": "geocom"}}, "station.toml")
    ok = parse_config({"campaign": {"mode": "sweep"}, "tracker": {"protocol": "emscon"}}, "station.toml")
    assert ok.campaign["mode"] == "sweep"
    with pytest.raises(InputError, match=r"campaign.stop_early: a sweep passes every calibration pose"):
        parse_config({"campaign": {"mode": "sweep", "stop_early": True}, "tracker": {"protocol": "emscon"}},
                     "station.toml")


@pytest.mark.parametrize("extra", [[], ["--tracker-protocol", "geocom"]])
def test_mode_sweep_with_geocom_is_refused_in_one_line_before_anything_starts(tmp_path, extra):
    db = tmp_path / "hil.db"
    proc = subprocess.run([sys.executable, "-m", "hil", "calibrate", "--sim", "--mode", "sweep", *extra,
                           "--db", str(db)], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "--mode sweep: GeoCOM cannot stream fast enough" in lines[0]
    assert "Traceback" not in proc.stderr and not db.exists()


def test_mode_sweep_with_a_geocom_config_is_refused(tmp_path):
    config = tmp_path / "station.toml"
    config.write_text('[robot]\naddress = "127.0.0.1"\n'
                      '[tracker]\nprotocol = "geocom"\nurl = "/dev/ttyUSB0"\n')
    proc = subprocess.run([sys.executable, "-m", "hil", "calibrate", "--config", str(config),
                           "--mode", "sweep", "--db", str(tmp_path / "hil.db")],
                          cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "GeoCOM cannot stream fast enough" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
