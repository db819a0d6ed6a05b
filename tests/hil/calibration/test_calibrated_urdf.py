"""The calibrated URDF: a chain's calibrated placements written into the user's file load in pinocchio
(and urdfdom) with exactly the calibrated chain's forward kinematics."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from hil.arm.chain import PRISMATIC, Chain, ur_chain
from hil.arm.urdf_chain import chain_from_urdf
from hil.calibration.calibrated_urdf import calibrated_origins, calibrated_urdf
from hil.calibration.urdf_rewrite import locate_joints
from hil.errors import InputError
from tests.hil.robot_urdfs import ARMS
from tests.hil.robot_urdfs import arm as arm_urdf

#: Arms whose tip link is reached through a fixed joint (the flange can be written) and the others.
FLANGE_WRITABLE = {"panda", "kinova", "ur5"}


def _moved(placement: pin.SE3, rng: np.random.Generator, scale: float) -> pin.SE3:
    """`placement` moved by a random se(3) step: a few millimetres and milliradians at scale 0.005."""
    return placement * pin.exp6(pin.Motion(rng.normal(scale=scale, size=6)))


def _chain_fk(chain: Chain, origins: list[pin.SE3], flange: pin.SE3, q: np.ndarray) -> pin.SE3:
    """The chain's forward kinematics by hand: origin_i · (rotation about / translation along z by q_i)."""
    T = pin.SE3.Identity()
    for origin, kind, value in zip(origins, chain.kinds, q, strict=True):
        motion = (pin.SE3(np.eye(3), np.array([0.0, 0.0, value])) if kind == PRISMATIC
                  else pin.SE3(pin.exp3(np.array([0.0, 0.0, value])), np.zeros(3)))
        T = T * origin * motion
    return T * flange


def _file_fk(xml: str, chain: Chain, q: np.ndarray) -> pin.SE3:
    """Pinocchio's forward kinematics of the URDF text: the tip link in the base link's frame."""
    assert chain.urdf is not None
    model = pin.buildModelFromXML(xml)
    v = np.zeros(model.nv)
    for name, value in zip(chain.joint_names, q, strict=True):
        v[model.joints[model.getJointId(name)].idx_v] = value
    config = pin.integrate(model, pin.neutral(model), v)  # a continuous joint's (cos, sin) too
    data = model.createData()
    pin.framesForwardKinematics(model, data, config)
    frame = {link: data.oMf[model.getFrameId(link, pin.FrameType.BODY)]
             for link in (chain.urdf.base, chain.urdf.tip)}
    return frame[chain.urdf.base].inverse() * frame[chain.urdf.tip]


def _close(a: pin.SE3, b: pin.SE3) -> tuple[float, float]:
    """(distance in m, angle in rad) between two placements."""
    angle = float(np.linalg.norm(pin.log3(a.rotation.T @ b.rotation)))
    return float(np.linalg.norm(a.translation - b.translation)), angle


@pytest.mark.parametrize(("arm", "base"), [(a, None) for a in sorted(ARMS)] + [("panda", "panda_link1")])
def test_the_written_urdf_has_the_calibrated_chains_forward_kinematics(arm: str, base: str | None) -> None:
    """Every joint placement (and the flange, where a fixed joint leads to the tip) moved by millimetres
    and milliradians: pinocchio's FK of the written file at random postures is the calibrated chain's to
    1e-9 m and rad, and only the joints written differ from the input's origins."""
    path, tip = arm_urdf(arm)
    chain = chain_from_urdf(path, base=base, tip=tip)
    rng = np.random.default_rng(11)
    origins = [_moved(o, rng, 0.005) for o in chain.origins]
    flange = _moved(chain.flange, rng, 0.005) if arm in FLANGE_WRITABLE else chain.flange
    written = calibrated_urdf(chain, origins, flange).decode("utf-8")
    original = path.read_text(encoding="utf-8")
    lo, hi = chain.sampling_range()
    for q in rng.uniform(lo, hi, size=(20, chain.dof)):
        nominal = _chain_fk(chain, list(chain.origins), chain.flange, q)
        assert max(_close(_file_fk(original, chain, q), nominal)) < 1e-9  # the chain is the file's
        calibrated = _chain_fk(chain, origins, flange, q)
        assert max(_close(_file_fk(written, chain, q), calibrated)) < 1e-9
        assert _close(calibrated, nominal)[0] > 1e-4  # the calibration shows at the tip
    before, after = locate_joints(original.encode()), locate_joints(written.encode())
    changed = {name for name in before if before[name].origin != after[name].origin}
    assert changed == set(calibrated_origins(chain, origins, flange))
    assert set(chain.joint_names) <= changed


def test_a_flange_with_no_fixed_joint_before_the_tip_is_refused_in_one_line() -> None:
    path, tip = arm_urdf("z1")
    chain = chain_from_urdf(path, tip=tip)
    assert chain.urdf is not None and chain.urdf.tip == chain.urdf.joints[-1].child
    moved = _moved(chain.flange, np.random.default_rng(1), 0.005)
    message = r"^z1\.urdf: the calibrated flange cannot be written: no fixed joint leads from 'link06' to"
    with pytest.raises(InputError, match=message) as caught:
        calibrated_urdf(chain, list(chain.origins), moved)
    assert "\n" not in str(caught.value)
    calibrated_urdf(chain, list(chain.origins), chain.flange)  # an unchanged flange needs no joint


def test_a_catalog_ur_has_no_urdf_to_rewrite() -> None:
    chain = ur_chain("ur5e")
    with pytest.raises(InputError, match="^ur5e: a catalog UR has no URDF of its own to rewrite$"):
        calibrated_urdf(chain, list(chain.origins), chain.flange)


@pytest.mark.parametrize("arm", sorted(ARMS))
def test_the_written_urdf_loads_in_urdfdom(arm: str, tmp_path: Path) -> None:
    """urdfdom's own parser (`check_urdf`, Debian liburdfdom-tools; .ci/run installs it) accepts it."""
    check_urdf = shutil.which("check_urdf")
    if check_urdf is None:
        pytest.skip("check_urdf (Debian liburdfdom-tools) is not installed: urdfdom not checked")
    source, tip = arm_urdf(arm)
    chain = chain_from_urdf(source, tip=tip)
    rng = np.random.default_rng(5)
    flange = _moved(chain.flange, rng, 0.005) if arm in FLANGE_WRITABLE else chain.flange
    path = tmp_path / "calibrated.urdf"
    path.write_bytes(calibrated_urdf(chain, [_moved(o, rng, 0.005) for o in chain.origins], flange))
    result = subprocess.run([check_urdf, str(path)], capture_output=True, text=True, timeout=60, check=False)
    assert result.returncode == 0, result.stdout + result.stderr


def test_identify_export_urdf_round_trip_is_hils_forward_kinematics() -> None:
    """A Panda identified from simulated measurements, exported with `export(..., "urdf")`: pinocchio's
    FK of the written file is hil's FK of the model (`Kinematics.flange_poses`, what ``hil fk`` gives)
    to 1e-9 m, and the file differs from the input only in joint origins."""
    from hil.arm.kinematics import Kinematics
    from hil.calibration.exports import export
    from hil.calibration.identification import identify
    from hil.calibration.measurements import Measurements
    from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth

    path, tip = arm_urdf("panda")
    chain = chain_from_urdf(path, tip=tip)
    rng = np.random.default_rng(8)
    truth = random_truth(chain, rng, rigid=True)
    q = random_configurations(chain, 60, rng)
    q_read, p = measure(truth, q, Noise(20e-6), rng)
    fit = identify(Measurements.from_arrays(q_read, p), chain)
    written = export({}, fit.geometry, "urdf")
    qv = random_configurations(chain, 20, rng)
    hil_fk = Kinematics(fit.geometry).flange_poses(qv)
    for k, row in enumerate(qv):
        assert np.linalg.norm(_file_fk(written, chain, row).translation - hil_fk[k, :3, 3]) < 1e-9
    before, after = locate_joints(path.read_bytes()), locate_joints(written.encode())
    changed = {n for n in before if before[n].origin != after[n].origin}
    assert changed <= set(chain.joint_names) | {"panda_joint8"}  # joint 8: the fixed joint to the tip
