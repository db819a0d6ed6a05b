"""The calibrated URDF of an arm read from a URDF: its chain's calibrated placements written back into
the user's own file as joint origins (`hil export --format urdf` for a `--urdf` model).

The chain (`hil.arm.urdf_chain`) folds the fixed joints in front of each actuated joint into its
placement and turns each axis onto z by a rotation A, so its placement i is
M_i = A_{i-1}ᵀ · F_i · O_i · A_i (F_i the folded fixed joints, O_i the URDF `<origin>`). A calibrated
M_i is written as the one origin O_i that reproduces it, `UrdfSource.urdf_origins`; the fixed joints and
the axes stay as the file has them. The flange (the tip link in the last joint's frame,
A_Nᵀ · F_tip) is written into the fixed joint that leads to the tip link: with F_tip = F_before · O_last,
O_last' = F_before⁻¹ · A_N · flange' (`joint_origin`). A tip that is the last actuated joint's own child
has no such joint; a calibrated flange is then refused rather than a joint added to the user's file.

Everything else stays byte for byte (`hil.calibration.urdf_rewrite`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from hil.arm.chain import Chain
from hil.calibration.urdf_rewrite import Origin, locate_joints, rewrite_joint_origins
from hil.errors import InputError

#: A flange this close to the nominal one (m, and rad of the rotation between them) counts as
#: unchanged: it needs no fixed joint to be written into. 1e-12 is round-off of SE(3) products on
#: metre-sized numbers, far below anything identification resolves.
FLANGE_UNCHANGED = 1e-12


def origin_placement(origin: Origin) -> pin.SE3:
    """The placement a URDF origin stands for (R = Rz(yaw)·Ry(pitch)·Rx(roll), then xyz)."""
    rotation = pin.rpy.rpyToMatrix(np.asarray(origin.rpy, dtype=float))
    return pin.SE3(rotation, np.asarray(origin.xyz, dtype=float))


def placement_origin(placement: pin.SE3) -> Origin:
    """The URDF origin of `placement` (pinocchio's `matrixToRpy`: pitch in [-π/2, π/2])."""
    xyz = tuple(float(v) for v in placement.translation)
    rpy = tuple(float(v) for v in pin.rpy.matrixToRpy(placement.rotation))
    return Origin(xyz, rpy)  # type: ignore[arg-type]


def joint_origin(fixed_part: pin.SE3, placement: pin.SE3, after: pin.SE3) -> pin.SE3:
    """The URDF `<origin>` O with fixed_part · O · after = `placement` (module docstring)."""
    return fixed_part.inverse() * placement * after.inverse()


def _flange_changed(nominal: pin.SE3, flange: pin.SE3) -> bool:
    step = pin.log6(nominal.inverse() * flange).vector
    return bool(np.max(np.abs(step)) > FLANGE_UNCHANGED)


def calibrated_origins(chain: Chain, origins: Sequence[pin.SE3], flange: pin.SE3) -> dict[str, Origin]:
    """The URDF `<origin>` of every joint the calibrated chain (`origins`, `flange`) changes, by joint
    name: each actuated joint's, and the tip's fixed joint's when the flange differs from the nominal.
    InputError when `chain` was not read from a URDF, or the flange changed and no fixed joint leads
    to the tip."""
    source = chain.urdf
    if source is None:
        raise InputError(f"{chain.name}: a catalog UR has no URDF of its own to rewrite")
    if len(origins) != chain.dof:
        raise ValueError(f"{len(origins)} origins for a chain of {chain.dof} joints")
    out = {name: placement_origin(o) for name, o in source.urdf_origins(list(origins)).items()}
    if _flange_changed(chain.flange, flange):
        sites = locate_joints(source.text.encode("utf-8"), source.file)
        last_child = source.joints[-1].child
        into = next((s for s in sites.values() if s.child == source.tip), None)
        if source.tip == last_child or into is None or into.kind != "fixed":
            raise InputError(f"{source.file}: the calibrated flange cannot be written: no fixed joint "
                             f"leads from {last_child!r} to the tip {source.tip!r} (give a tip link below a "
                             "fixed joint, or keep the flange nominal)")
        before = source.tip_fixed * origin_placement(into.origin).inverse()
        axis = pin.SE3(source.joints[-1].axis_rotation, np.zeros(3))
        out[into.name] = placement_origin(joint_origin(before, axis * flange, pin.SE3.Identity()))
    return out


def calibrated_urdf(chain: Chain, origins: Sequence[pin.SE3], flange: pin.SE3) -> bytes:
    """The bytes of the URDF `chain` was read from, with the joint origins of the calibrated chain
    (`origins`, `flange`: `calibrated_origins`) and every other byte as the file has it."""
    changed = calibrated_origins(chain, origins, flange)
    assert chain.urdf is not None  # calibrated_origins refuses a chain without one
    return rewrite_joint_origins(chain.urdf.text.encode("utf-8"), changed, chain.urdf.file)
