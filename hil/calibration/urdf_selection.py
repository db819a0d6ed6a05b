"""Pose selection for an arm read from its URDF: hil's chain as the selector's `PoseModel`.

`hil.calibration.selection.SelectionModel` is a UR's: its capsules follow a UR's physical layout, its
singularity measures are a UR's, its parameters include compliance and joint errors. For any other
serial arm the same selector runs on `UrdfSelectionModel`:

* **candidates** inside the URDF's joint limits (one turn of a joint that turns further,
  `selector.candidates.sampling_box`);
* **self-collision** from the URDF's own collision geometry (`hil.arm.urdf_collision`; capsules where
  it has none, which its `note` says);
* **line of sight and the floor** against capsules between the chain's joint origins
  (`selector.arm.ChainShape`), of the radii `hil.arm.urdf_collision.capsule_radii` gives the arm;
  the SMR's own capsule is a UR's tool capsule (`selector.arm.UR5E_RADII`'s last);
* **SMR angle to the tracker**: the last full-turn revolute joint that turns the SMR's opening axis is
  the one `aim_wrist` draws over the angles facing the tracker (`aim_joint`);
* **the information matrix** from the generic kinematics (`hil.arm.kinematics` on the chain): the
  identifiable set of the chain (pivoted QR at a generic point), less what this SMR offset leaves
  unobservable (the same check as a UR's, `drop_unobservable`);
* the UR singularity margins (wrist, elbow, shoulder) do not apply and are switched off
  (`NON_UR_DISABLED`): a design that maximises the information keeps away from poses that lose it.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence

import numpy as np

from hil.arm.chain import REVOLUTE, Chain
from hil.arm.geometry import Geometry, look_at_tracker
from hil.arm.kinematics import Kinematics, identifiable_parameters, parameter_layout
from hil.arm.urdf_collision import UrdfSelfCollision, capsule_radii, chain_frames
from hil.calibration.selection_parameters import drop_unobservable, expected_magnitude
from selector.arm import UR5E_RADII, ChainShape

#: Where the tracker is assumed to stand for the Jacobian when the user gives none (m, base frame), as
#: for a UR (`hil.calibration.selection.DEFAULT_TRACKER_FOR_JACOBIAN`): the tracker pose only
#: reparametrises the tracker columns, which leaves O1 unchanged.
DEFAULT_TRACKER_FOR_JACOBIAN = (2.5, 0.0, 0.5)
#: The constraints measured on a UR's structure, off for every other arm.
NON_UR_DISABLED = frozenset({"wrist", "elbow", "shoulder"})
#: A joint turns the SMR's opening axis when the axis is, on average over postures, farther than this
#: from parallel to the joint's axis (|cos| below it): joint 6 of a UR turns about the axis itself.
AIM_PARALLEL = 0.95


class UrdfSelectionModel:
    """`selector.model.PoseModel` of a URDF chain + SMR + tracker (module docstring)."""

    def __init__(self, chain: Chain, smr: Sequence[float] = (0.0, 0.0, 0.045),
                 tracker: Sequence[float] | None = None, *,
                 urdf_path: str | os.PathLike[str] | None = None,
                 opening_axis: Sequence[float] = (0.0, 0.0, 1.0)) -> None:
        self.chain = chain
        self.name = chain.name
        position = DEFAULT_TRACKER_FOR_JACOBIAN if tracker is None else tracker
        self.geometry = Geometry.nominal(chain, smr=np.asarray(smr, float), tracker=look_at_tracker(position))
        self.kinematics = Kinematics(self.geometry)
        self.lower, self.upper = chain.lower.copy(), chain.upper.copy()
        self.max_joint_speed = chain.velocity.copy()
        self.smr = self.geometry.smr.copy()
        self.collision = UrdfSelfCollision(chain, urdf_path)
        self.collides = self.collision.collides
        self.arm = self._shape()
        self.aim_joint = self._aim_joint(np.asarray(opening_axis, float))
        lo, hi = chain.sampling_range()
        q = np.random.default_rng(11).uniform(lo, hi, size=(max(120, 2 * parameter_layout(chain.dof).size),
                                                            chain.dof))
        names = parameter_layout(chain.dof).names
        self.parameters, self.unobservable = drop_unobservable(
            self.kinematics, q, identifiable_parameters(chain), names)
        self.parameter_names = tuple(names[i] for i in self.parameters)
        self.parameter_scale = np.array([expected_magnitude(n, chain.name) for n in self.parameter_names])

    def _shape(self) -> ChainShape:
        """Capsules between the joint origins, sized by the arm's reach; the leading capsules that stay
        at one height in every posture (the base, a shoulder turning about the vertical) stand on the
        mounting surface and are not held above the floor."""
        dof = self.chain.dof
        radii = capsule_radii(self.chain)
        lo, hi = self.chain.sampling_range()
        q = np.random.default_rng(3).uniform(lo, hi, size=(64, dof))
        z = chain_frames(self.chain, q)[:, :, 2, 3]  # (64, dof + 2): base, joints, flange heights
        fixed = np.ptp(z, axis=0) < 1e-9
        floor_from = 0
        while floor_from < dof + 1 and fixed[floor_from] and fixed[floor_from + 1]:
            floor_from += 1
        return ChainShape(radii=(*map(float, radii), UR5E_RADII[-1]), pairs=(), floor_from=floor_from)

    def _aim_joint(self, opening_axis: np.ndarray) -> int | None:
        """The last revolute joint that turns a full turn and turns the SMR's opening axis (module
        docstring), or None."""
        lo, hi = self.chain.sampling_range()
        q = np.random.default_rng(5).uniform(lo, hi, size=(32, self.chain.dof))
        F = self.frames(q)
        axis = F[:, -1, :3, :3] @ (opening_axis / np.linalg.norm(opening_axis))
        for k in reversed(range(self.chain.dof)):
            if self.chain.kinds[k] != REVOLUTE or hi[k] - lo[k] < 2 * math.pi - 1e-9:
                continue
            if np.mean(np.abs(np.einsum("ni,ni->n", F[:, k, :3, 2], axis))) < AIM_PARALLEL:
                return k
        return None

    def frames(self, q: np.ndarray) -> np.ndarray:
        """(N, n + 1, 4, 4) joint frames after their motion and the flange, base frame (batched)."""
        return chain_frames(self.chain, q)[:, 1:]

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """(N, 3, n) identification Jacobian of the observable parameters (hil's pinocchio model)."""
        return self.kinematics.jacobian(q, self.parameters)
