"""Identification of arms from their URDFs: a UR5e through a URDF of its DH table identifies exactly
as through the catalog, other arms recover a synthetic truth, and what stays UR-only is refused."""

from __future__ import annotations

import numpy as np
import pytest

from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.arm.urdf_chain import chain_from_text, chain_from_urdf
from hil.calibration.exports import to_urdf
from hil.calibration.identification import identify
from hil.calibration.measurements import Measurements
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from hil.errors import InputError
from tests.hil.robot_urdfs import arm


def _data(robot, seed: int, count: int = 40):
    rng = np.random.default_rng(seed)
    truth = random_truth(robot, rng, rigid=True)
    q, p = measure(truth, random_configurations(robot, count, rng), Noise(tracker_sigma=20e-6), rng)
    return truth, Measurements.from_arrays(q, p, source="m.csv")


def test_ur5e_through_its_urdf_identifies_as_the_catalog_path() -> None:
    chain = chain_from_text(to_urdf(Geometry.nominal("ur5e")), tip="tool0", source="ur5e.urdf")
    _, meas = _data("ur5e", 4)
    ours, theirs = identify(meas, chain), identify(meas, "ur5e")
    np.testing.assert_array_equal(ours.indices, theirs.indices)
    assert ours.names == theirs.names
    assert ours.rms == pytest.approx(theirs.rms, rel=1e-6)
    Q = random_configurations("ur5e", 200, np.random.default_rng(9))
    np.testing.assert_allclose(Kinematics(ours.geometry).points(Q), Kinematics(theirs.geometry).points(Q),
                               atol=1e-9)


@pytest.mark.parametrize("name", ["panda", "kinova", "z1"])
def test_an_arm_from_its_urdf_recovers_its_truth(name: str) -> None:
    path, tip = arm(name)
    chain = chain_from_urdf(path, tip=tip)
    truth, meas = _data(chain, 2)
    fit = identify(meas, chain)
    assert len(fit.indices) == 4 * chain.dof + 3
    Q = random_configurations(chain, 300, np.random.default_rng(8))
    nominal = Geometry.nominal(chain, smr=fit.geometry.smr, tracker=fit.geometry.tracker)
    error = np.linalg.norm(Kinematics(truth).points(Q) - Kinematics(fit.geometry).points(Q), axis=1)
    before = np.linalg.norm(Kinematics(truth).points(Q) - Kinematics(nominal).points(Q), axis=1)
    assert np.sqrt(np.mean(error**2)) < 60e-6 < np.sqrt(np.mean(before**2))
    assert all(n.startswith(("joint", "flange", "smr", "tracker")) for n in fit.names)
    # the model file's geometry block round-trips with its URDF
    back = Geometry.from_dict(fit.geometry.to_dict(), "model.json")
    assert back.chain == chain
    np.testing.assert_allclose(Kinematics(back).points(Q), Kinematics(fit.geometry).points(Q), atol=1e-12)


def test_a_column_count_that_is_not_the_chains_is_one_line() -> None:
    path, tip = arm("panda")
    chain = chain_from_urdf(path, tip=tip)
    _, meas = _data("ur5e", 1)
    with pytest.raises(InputError, match=r"m.csv: 6 joint columns, but the panda has 7 joints"):
        identify(meas, chain)


def test_compliance_and_realistic_truths_are_ur_only() -> None:
    path, tip = arm("panda")
    chain = chain_from_urdf(path, tip=tip)
    _, meas = _data(chain, 1)
    with pytest.raises(InputError, match="Universal Robots arms only"):
        identify(meas, chain, compliance=True)
    with pytest.raises(InputError, match="Universal Robots arms only"):
        random_truth(chain, np.random.default_rng(0))


def test_a_model_whose_urdf_text_was_changed_is_refused() -> None:
    path, tip = arm("kinova")
    doc = Geometry.nominal(chain_from_urdf(path, tip=tip)).to_dict()
    doc["urdf"]["text"] = doc["urdf"]["text"].replace("0.15675", "0.15676")
    with pytest.raises(InputError, match="model.json: field 'urdf.text' does not match"):
        Geometry.from_dict(doc, "model.json")
