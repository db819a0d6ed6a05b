"""The simulated station's configuration says what its arm's operator knows: payload, mounting and
where the SMR sits on the flange."""

from __future__ import annotations

import numpy as np

from hil.arm.payload import Payload, gravity_of_mounting
from hil.station.simulated import operator_knowledge, simulated_station


def test_the_config_carries_the_truths_payload_but_not_its_compliance() -> None:
    with simulated_station("ur5e", speed=10.0, seed=2) as (config, identity, truth, _sim):
        assert truth["compliance"] and truth["thermal"]  # a real arm, hidden
        assert config.payload == Payload.from_dict(truth["payload"])
        assert identity["robot"]["payload"] == truth["payload"]
        assert list(config.values["robot"]["mounting"]) == [0.0, 0.0, 0.0]
        assert "compliance" not in config.values["robot"]


def test_a_rigid_station_has_nothing_on_its_flange() -> None:
    with simulated_station("ur5e", speed=10.0, seed=2, rigid=True) as (config, _identity, truth, _sim):
        assert "compliance" not in truth and "payload" not in truth
        assert config.payload is None


def test_the_mounting_turns_floor_gravity_into_the_truths() -> None:
    for rpy in ((0.3, -0.2, 0.0), (np.pi, 0.0, 0.0), (0.0, 1.2, 0.0), (-0.5, 0.4, 1.0)):
        g = gravity_of_mounting(rpy)
        mounting = operator_knowledge({"gravity": g.tolist()})["robot__mounting"]
        np.testing.assert_allclose(gravity_of_mounting(mounting), g, atol=1e-12)
    assert operator_knowledge({}) == {}


def test_the_config_knows_the_smr_offset_from_its_holders_drawing() -> None:
    """Where the SMR sits on the flange is on the SMR holder's drawing: the configuration carries the
    truth's offset to the drawing's 0.5 mm (a MOVEB run without a model assumed (0, 0, 45) mm while the
    simulated SMR sat at (1.0, 36.0, 25.2) mm, and reported 9.5 mm of path error on a tilting seam)."""
    known = operator_knowledge({"smr": [0.00094573, 0.0360371, 0.02576638]})["smr__offset"]
    np.testing.assert_allclose(known, [0.001, 0.036, 0.026], atol=1e-12)
    with simulated_station("ur5e", speed=10.0, seed=2) as (config, _identity, truth, _sim):
        offset = np.array(config.values["smr"]["offset"])
        assert np.abs(offset - np.array(truth["smr"])).max() <= 0.25e-3
