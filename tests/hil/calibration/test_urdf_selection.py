"""Pose selection for arms read from their URDFs: the model the selector gets, and candidates that keep
to the URDF's limits, its collision geometry, and the tracker's line of sight and SMR angle."""

from __future__ import annotations

import math

import numpy as np
import pytest

import selector
from hil.arm.urdf_chain import chain_from_urdf
from hil.calibration.selection import constraints_for, select_poses, selection_model
from hil.calibration.urdf_selection import UrdfSelectionModel
from hil.errors import InputError
from selector.candidates import Constraints, evaluate, generate_candidates, sampling_box
from tests.hil.robot_urdfs import arm as arm_urdf

TRACKER = (1.8, 0.4, 0.5)


def _model(name: str, smr: tuple[float, float, float] = (0.02, -0.01, 0.045)) -> UrdfSelectionModel:
    path, tip = arm_urdf(name)
    return UrdfSelectionModel(chain_from_urdf(path, tip=tip), smr, TRACKER, urdf_path=path)


@pytest.mark.parametrize("name", ["panda", "kinova", "z1"])
def test_frames_are_the_pinocchio_kinematics(name: str) -> None:
    """The selector's batched frames (numpy products of the chain) are hil's pinocchio kinematics'."""
    model = _model(name)
    lo, hi = model.chain.sampling_range()
    q = np.random.default_rng(2).uniform(lo, hi, size=(20, model.chain.dof))
    assert np.allclose(model.frames(q), model.kinematics.joint_frames(q), atol=1e-12)
    assert model.jacobian(q).shape == (20, 3, len(model.parameters))


def test_sampling_keeps_a_joints_limits_of_less_than_a_turn() -> None:
    """Kinova's joint 2 turns between 0.82 and 5.46 rad: drawn there, not clipped to ±π; its continuous
    joints over one turn; a UR's joints over ±π as before."""
    model = _model("kinova")
    lo, hi = sampling_box(model, Constraints())
    assert lo[1] == pytest.approx(0.820304748437) and hi[1] == pytest.approx(5.46288055874)
    assert lo[0] == pytest.approx(-math.pi) and hi[0] == pytest.approx(math.pi)
    ur = selection_model("ur5e", (0.0, 0.0, 0.045), TRACKER)
    lo, hi = sampling_box(ur, Constraints())
    assert np.allclose(lo, -math.pi) and np.allclose(hi, math.pi)


def test_the_aim_joint_of_a_ur_read_from_its_urdf_is_its_wrist_2() -> None:
    """The joint drawn to face the SMR to the tracker: on a UR5 from its URDF, joint 5 (index 4), the one
    a UR's selection turns; none on a Panda (no joint of it turns a full turn)."""
    assert _model("ur5").aim_joint == 4
    assert _model("panda").aim_joint is None


@pytest.mark.parametrize("name", ["panda", "kinova", "z1"])
def test_candidates_keep_every_constraint(name: str) -> None:
    """Every candidate lies inside the URDF's limits, is free of self-collision on the URDF's meshes,
    faces the tracker within the half-angle with the beam clear of the links, and the UR singularity
    measures are off."""
    model = _model(name)
    constraints = constraints_for(model, Constraints(tracker=TRACKER))
    assert {"wrist", "elbow", "shoulder"}.isdisjoint(constraints.enabled())
    cands = generate_candidates(model, 300, constraints, seed=1)
    assert len(cands) == 300
    assert np.all(model.chain.within_limits(cands.q))
    assert not np.any(model.collision.collides(cands.q))
    passes, smr = evaluate(model, cands.q, constraints)
    assert all(np.all(ok) for ok in passes.values())
    assert np.allclose(smr, cands.smr)
    assert cands.jacobian.shape == (300, 3, len(model.parameters))


def test_the_ur_singularity_measures_are_refused_for_another_arm() -> None:
    model = _model("panda")
    with pytest.raises(selector.SelectorError, match="singularity measures are a UR's"):
        evaluate(model, np.zeros((1, 7)), Constraints(tracker=TRACKER))


def test_compliance_is_refused_for_a_urdf_arm_in_one_line() -> None:
    path, tip = arm_urdf("z1")
    with pytest.raises(InputError, match="compliance is modelled for Universal Robots arms only"):
        selection_model(chain_from_urdf(path, tip=tip), (0.0, 0.0, 0.045), TRACKER, compliance=True)


def test_select_poses_for_a_urdf_arm_beats_random_poses() -> None:
    """The whole pipeline on the Z1: a report naming the URDF and its self-collision check, poses from
    the candidates, and a design whose information (O1) is above random poses' of the same count."""
    path, tip = arm_urdf("z1")
    chain = chain_from_urdf(path, tip=tip)
    common = {"candidates": 1500, "seed": 4, "smr": (0.02, -0.01, 0.045), "bound": False,
              "constraints": Constraints(tracker=TRACKER), "urdf_path": str(path)}
    report = select_poses(chain, 30, **common)
    assert report["robot"] == chain.name and report["count"] == 30
    assert report["urdf"]["sha256"] == chain.urdf.sha256 and report["urdf"]["tip"] == tip  # type: ignore[union-attr]
    assert report["self_collision"]["check"] == "meshes"
    assert "wrist" in report["constraints"]["disabled"]
    assert np.all(chain.within_limits(np.array(report["poses"])))
    random = select_poses(chain, 30, method="random", **common)
    assert report["o1"] > 1.15 * random["o1"]  # 1.28× measured (seed 4)
