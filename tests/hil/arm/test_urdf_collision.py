"""Self-collision of a URDF arm: its collision meshes in batches, which pairs are checked, and capsules
where the URDF has no geometry."""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest

from hil.arm.urdf_chain import chain_from_text, chain_from_urdf
from hil.arm.urdf_collision import UrdfSelfCollision, capsule_radii, chain_frames
from selector.arm import COLLISION_MARGIN
from tests.hil.robot_urdfs import arm as arm_urdf


def _check(name: str, **kwargs: object) -> UrdfSelfCollision:
    path, tip = arm_urdf(name)
    return UrdfSelfCollision(chain_from_urdf(path, tip=tip), path, **kwargs)  # type: ignore[arg-type]


def _random_q(check: UrdfSelfCollision, n: int, seed: int) -> np.ndarray:
    lo, hi = check.chain.sampling_range()
    return np.random.default_rng(seed).uniform(lo, hi, size=(n, check.chain.dof))


@pytest.mark.parametrize("arm", ["panda", "kinova", "z1", "so100", "ur5"])
def test_the_batched_check_is_pinocchios_distance_below_the_margin(arm: str) -> None:
    """`collides` (GeometryPool, one call per batch, stop at the first contact) is, posture by posture,
    whether pinocchio's distance between some checked pair is below the margin."""
    check = _check(arm)
    assert check.kind == "meshes"
    q = _random_q(check, 120, 1)
    got = check.collides(q)
    model, geom = check._model, check._geom
    data, geom_data = model.createData(), pin.GeometryData(geom)
    expected = []
    for config in check._configs(q).T:
        pin.computeDistances(model, data, geom, geom_data, config)
        expected.append(min(r.min_distance for r in geom_data.distanceResults) < COLLISION_MARGIN)
    assert np.array_equal(got, np.array(expected))
    assert 0 < got.sum() < len(q)  # the sample holds both


def test_pairs_are_the_links_that_can_meet() -> None:
    """Panda: a link is never checked against its neighbours, the fingers belong to the hand (below the
    last joint), the base is checked against the hand."""
    check = _check("panda")
    names = {(check._geom.geometryObjects[p.first].name, check._geom.geometryObjects[p.second].name)
             for p in check._geom.collisionPairs}
    links = {tuple(sorted(n.rsplit("_", 1)[0] for n in pair)) for pair in names}
    assert ("panda_hand", "panda_link0") in links and ("panda_link5", "panda_link7") in links
    assert ("panda_link6", "panda_link7") not in links and ("panda_hand", "panda_link7") not in links
    assert not any(("finger" in a and "hand" in b) or ("finger" in b and "hand" in a) for a, b in links)
    assert ("panda_link3", "panda_link4") not in links and ("panda_leftfinger", "panda_link7") not in links


def test_a_documented_free_posture_is_free_and_a_folded_one_collides() -> None:
    """UR5 upright (q2 = q4 = −π/2, the UR 'home' of the transit postures) is free; the forearm folded
    back onto the upper arm (elbow at 170°) is not. Panda's ready posture (franka_ros's
    `ready` joint values 0, −π/4, 0, −3π/4, 0, π/2, π/4) is free."""
    upright_and_folded = np.array([[0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0],
                                   [0.0, -np.pi / 2, np.radians(170), -np.pi / 2, 0.0, 0.0]])
    assert _check("ur5").collides(upright_and_folded).tolist() == [False, True]
    ready = np.array([[0.0, -np.pi / 4, 0.0, -3 * np.pi / 4, 0.0, np.pi / 2, np.pi / 4]])
    assert not _check("panda").collides(ready)[0]


def test_a_urdf_without_collision_geometry_gets_capsules_and_says_so() -> None:
    path, tip = arm_urdf("ur5")
    text = re.sub(r"<collision>.*?</collision>", "", path.read_text(encoding="utf-8"), flags=re.S)
    chain = chain_from_text(text, tip=tip, source="bare.urdf")
    check = UrdfSelfCollision(chain)
    assert check.kind == "capsules"
    assert "\n" not in check.note and "the URDF has no collision geometry on the chain" in check.note
    q = np.array([[0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0],
                  [0.0, -np.pi / 2, np.radians(170), -np.pi / 2, 0.0, 0.0]])
    assert check.collides(q).tolist() == [False, True]


def test_a_mesh_that_cannot_be_found_falls_back_to_capsules_naming_it() -> None:
    path, tip = arm_urdf("ur5")
    check = UrdfSelfCollision(chain_from_urdf(path, tip=tip))  # no urdf_path: package:// not found
    assert check.kind == "capsules"
    assert "could not be loaded" in check.note and "base.stl" in check.note


def test_capsules_follow_the_chains_joint_origins() -> None:
    """The capsule check by hand on a few postures: the distance between capsule segments (joint origin
    to joint origin, from `chain_frames`) below 2·radius + margin."""
    check = _check("so100", capsules=True)
    q = _random_q(check, 200, 3)
    points = chain_frames(check.chain, q)[:, :, :3, 3]
    a, b = check._pairs[:, 0], check._pairs[:, 1]
    s = np.linspace(0.0, 1.0, 101)[:, None, None, None]  # (S, 1, 1, 1) along each segment
    pa = points[None, :, a] + s * (points[None, :, a + 1] - points[None, :, a])  # (S, N, P, 3)
    pb = points[None, :, b] + s * (points[None, :, b + 1] - points[None, :, b])
    d = np.linalg.norm(pa[:, None] - pb[None], axis=-1).min(axis=(0, 1))  # sampled distance (N, P)
    expected = np.any(d < check.radii[a] + check.radii[b] + COLLISION_MARGIN, axis=1)
    got = check.collides(q)
    assert np.all(got[expected])  # the sampled distance is never below the true one
    assert np.mean(got != expected) < 0.02 and 0 < expected.sum() < len(q)
    radii = capsule_radii(check.chain)
    assert radii[0] > radii[-1] and len(radii) == check.chain.dof + 1


def test_chain_frames_are_pinocchios() -> None:
    path, tip = arm_urdf("panda")
    chain = chain_from_urdf(path, tip=tip)
    q = np.random.default_rng(4).uniform(-2, 2, size=(5, chain.dof))
    model = pin.buildModelFromXML(path.read_text(encoding="utf-8"))
    data = model.createData()
    frames = chain_frames(chain, q)
    for k, row in enumerate(q):
        config = pin.neutral(model)
        for name, value in zip(chain.joint_names, row, strict=True):
            config[model.joints[model.getJointId(name)].idx_q] = value
        pin.framesForwardKinematics(model, data, config)
        tip_frame = data.oMf[model.getFrameId(tip, pin.FrameType.BODY)]
        assert np.allclose(frames[k, -1], tip_frame.homogeneous, atol=1e-12)


def test_configurations_of_the_wrong_width_are_refused() -> None:
    with pytest.raises(ValueError, match="configurations of 6 joints for a chain of 7"):
        _check("panda").collides(np.zeros((2, 6)))
