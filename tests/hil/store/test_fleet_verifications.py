"""Verification campaigns (ISO 9283, `hil verify`) in a fleet's store: kept apart from calibrations."""

from __future__ import annotations

from pathlib import Path

from hil.store import RobotIdentity, Store
from hil.store.fleet import current_model, fleet, robot_history
from tests.hil.fleet_data import STEADY, _config

RESULT = {"format": "hil-verification/1", "cycles": 30,
          "results": {"uncompensated": {"AP_max": 1.0e-3, "RP_max": 1.1e-5},
                      "compensated": {"AP_max": 9.0e-6, "RP_max": 1.3e-5}}}


def _verify(location: Path | str, status: str = "accepted") -> str:
    with Store(location) as store:
        cid = store.create_campaign(_config("eol-cell-1", "ur5e"), RobotIdentity("ur5e", STEADY),
                                    plan={"kind": "verification", "cycles": 30})
        store.set_status(cid, status, result=RESULT)
    return cid


def test_a_verification_is_listed_as_one_and_not_as_a_calibration(fleet_store_location: Path | str) -> None:
    with Store(fleet_store_location) as store:
        before = {r.serial: r for r in fleet(store)}
        history_before = robot_history(store, STEADY)
        model_before = current_model(store, STEADY)[0]
    cid = _verify(fleet_store_location)
    with Store(fleet_store_location) as store:
        after = {r.serial: r for r in fleet(store)}
        history = robot_history(store, STEADY)
        summary = next(c for c in store.campaigns(None) if c.id == cid)
        assert current_model(store, STEADY)[0] == model_before
    # the fleet's "last calibration", the count and the current model ignore it ...
    assert after[STEADY].last == before[STEADY].last
    assert after[STEADY].calibrations == before[STEADY].calibrations
    assert [c.id for c in history.calibrations] == [c.id for c in history_before.calibrations]
    # ... the robot's history lists it with its figures, and `hil history` knows what it is
    assert [v.id for v in history.verifications] == [cid]
    v = history.verifications[0]
    assert v.ap_max == {"uncompensated": 1.0e-3, "compensated": 9.0e-6}
    assert v.rp_max["compensated"] == 1.3e-5 and v.cycles == 30 and v.status == "accepted"
    assert summary.kind == "verification"
    assert all(c.kind == "calibration" for c in store_campaigns(fleet_store_location) if c.id != cid)


def test_an_unfinished_verification_has_no_figures(fleet_store_location: Path | str) -> None:
    with Store(fleet_store_location) as store:
        cid = store.create_campaign(_config("eol-cell-1", "ur5e"), RobotIdentity("ur5e", STEADY),
                                    plan={"kind": "verification"})
        history = robot_history(store, STEADY)
    assert [(v.id, v.ap_max, v.rp_max) for v in history.verifications] == [(cid, {}, {})]


def store_campaigns(location: Path | str) -> list:
    with Store(location) as store:
        return store.campaigns(None)


def test_robot_and_history_commands_show_the_verification(fleet_store_location: Path | str, capsys) -> None:
    from hil.cli import main

    cid = _verify(fleet_store_location)
    assert main(["robot", STEADY, "--db", str(fleet_store_location)]) == 0
    out = capsys.readouterr().out
    section = out[out.index("verifications (ISO 9283"):]
    row = next(line for line in section.splitlines() if line.strip().startswith(cid))
    assert row.split()[-3:] == ["1.000", "0.009", "0.013"]  # AP uncompensated, compensated, worst RP (mm)
    assert main(["history", "--db", str(fleet_store_location), "--limit", "50"]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith(cid))
    assert " verified " in line
