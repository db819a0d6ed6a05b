"""Self-collision of an arm read from a URDF: its own collision geometry, or capsules where it has none.

A pose selector draws thousands of candidate postures and must drop those that fold the arm onto
itself. For a URDF arm the best description of its links is the file's own `<collision>`
geometry (meshes, boxes, cylinders), which pinocchio loads (`buildGeomFromUrdfString`, coal underneath)
and checks in batches (`computeCollisionsInParallel` on a `GeometryPool`: one C++ call per batch, no
Python loop per posture).

**Which pairs.** Each geometry object belongs to one link of the chain: position 0 for the base link
and anything rigid with it, i for the links carried by chain joint i (the fixed joints after it
included), N for what hangs below the last joint (a hand, fingers). Objects of the same or of
neighbouring positions touch by construction and are never checked. Of the others, a pair already in
contact at the *reference posture* (the middle of every joint's range) is taken to overlap by
construction too — meshes drawn generously around a joint, a capsule ending where the next link's
starts — and is left out; `disabled` names them, and the note says how many.

**No collision geometry on the chain** (or a mesh file that cannot be found): capsules around the
chain's links instead — from each joint's origin to the next one's, the base origin to joint 1, the
last joint to the tip — tapering from base to wrist as a UR's do, scaled with the arm's size
(`capsule_radii`); the note says so in one line, since capsules are coarser than the real housings.

Both checks count a posture as colliding when two checked bodies come closer than `margin` (surface to
surface), the selector's `COLLISION_MARGIN` by default.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from hil.arm.chain import PRISMATIC, Chain
from selector.arm import COLLISION_MARGIN, UR5E_RADII, segment_distance

#: A UR5e's reach (m): Universal Robots, UR5e technical specifications (850 mm). The capsules of an arm
#: without collision geometry taper from a UR5e's base housing radius to its wrist's
#: (`selector.arm.UR5E_RADII`), scaled as hil scales a UR's capsules (`hil.arm.self_collision.arm_shape`:
#: by size^0.6) with the arm's reach against this one. Using a UR's housings for another arm is an
#: assumption (no URDF without geometry says how thick its links are); the scaling keeps a desktop
#: arm's capsules desktop-sized.
UR5E_REACH = 0.85
#: Postures checked per C++ call: a few thousand keep the batch's arrays small and the call long
#: enough that the Python overhead per batch does not count.
BATCH = 4096


def capsule_radii(chain: Chain) -> np.ndarray:
    """(dof + 1,) radii (m) of the capsules base→joint 1, …, joint n→tip of an arm without collision
    geometry: a UR5e's base radius tapering linearly to its wrist's, scaled by (reach / 0.85 m)^0.6
    (`UR5E_REACH`)."""
    scale = (max(tip_reach(chain), 1e-3) / UR5E_REACH) ** 0.6
    t = np.linspace(0.0, 1.0, chain.dof + 1)
    return scale * (UR5E_RADII[0] + t * (UR5E_RADII[-2] - UR5E_RADII[0]))


def chain_frames(chain: Chain, q: np.ndarray) -> np.ndarray:
    """(N, dof + 2, 4, 4): the base frame, each joint's frame after its motion, and the tip (flange)
    frame, in the base frame, for configurations `q` (N, dof); batched products of the chain's
    placements (no pinocchio call per posture)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n = q.shape[0]
    T = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    out = [T]
    for origin, kind, angle in zip(chain.origins, chain.kinds, q.T, strict=True):
        motion = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
        if kind == PRISMATIC:
            motion[:, 2, 3] = angle
        else:
            c, s = np.cos(angle), np.sin(angle)
            motion[:, 0, 0], motion[:, 0, 1], motion[:, 1, 0], motion[:, 1, 1] = c, -s, s, c
        T = T @ origin.homogeneous @ motion
        out.append(T)
    out.append(T @ chain.flange.homogeneous)
    return np.stack(out, axis=1)


def tip_reach(chain: Chain) -> float:
    """The arm's reach (m): the farthest the tip gets from joint 1's origin over 512 postures drawn
    inside the limits (seeded), what its capsules are sized by (a UR5e's: 0.85 m from its base axis)."""
    lo, hi = chain.sampling_range()
    q = np.random.default_rng(0).uniform(lo, hi, size=(512, chain.dof))
    frames = chain_frames(chain, q)
    return float(np.max(np.linalg.norm(frames[:, -1, :3, 3] - frames[:, 1, :3, 3], axis=1)))


class UrdfSelfCollision:
    """The self-collision check of a chain read from a URDF (module docstring).

    `urdf_path` is where the URDF was read from: its directories are where `package://` mesh paths
    are looked for (with `package_dirs` and ROS_PACKAGE_PATH). `capsules=True` ignores the file's
    geometry (for comparisons). `note` is the one line to show the user.
    """

    def __init__(self, chain: Chain, urdf_path: str | os.PathLike[str] | None = None,
                 package_dirs: Sequence[str | os.PathLike[str]] = (), margin: float = COLLISION_MARGIN,
                 capsules: bool = False, threads: int = 1) -> None:
        if chain.urdf is None:
            raise ValueError("a URDF self-collision check needs a chain read from a URDF")
        self.chain = chain
        self.margin = margin
        self.threads = threads
        self.disabled: list[tuple[str, str]] = []
        self._pool: pin.GeometryPool | None = None
        reason = "asked for" if capsules else ""
        if not capsules:
            reason = self._load_meshes(urdf_path, package_dirs)
        if reason:
            self.kind = "capsules"
            self._setup_capsules()
            self.note = (f"self-collision: capsules of {self.radii.max() * 1000:.0f} to "
                         f"{self.radii.min() * 1000:.0f} mm around the chain's links "
                         f"({reason}; {len(self._pairs)} pairs checked, {len(self.disabled)} touching at the "
                         "mid-range posture left out)")
        else:
            self.kind = "meshes"
            self.note = (f"self-collision: the URDF's collision geometry ({self._ngeoms} bodies, "
                         f"{self._npairs} pairs checked, {len(self.disabled)} touching at the mid-range "
                         "posture left out)")

    # --- the URDF's geometry -------------------------------------------------------------------------

    def _load_meshes(self, urdf_path: str | os.PathLike[str] | None,
                     package_dirs: Sequence[str | os.PathLike[str]]) -> str:
        """Load the collision geometry and choose its pairs; the reason to fall back to capsules, or ''."""
        source = self.chain.urdf
        assert source is not None
        dirs = [str(d) for d in package_dirs]
        if urdf_path is not None:
            dirs += [str(p) for p in Path(urdf_path).resolve().parents]
        model = pin.buildModelFromXML(source.text)
        try:
            geom = pin.buildGeomFromUrdfString(model, source.text, pin.COLLISION, package_dirs=dirs)
        except (ValueError, RuntimeError, OSError) as exc:
            first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
            return f"the URDF's collision geometry could not be loaded: {first}"
        chain_ids = [model.getJointId(name) for name in self.chain.joint_names]
        base_joint = model.frames[model.getFrameId(source.base, pin.FrameType.BODY)].parentJoint
        position = _chain_positions(model, chain_ids, base_joint)
        owned = [(k, position[g.parentJoint]) for k, g in enumerate(geom.geometryObjects)
                 if position.get(g.parentJoint) is not None]
        if not owned:
            return "the URDF has no collision geometry on the chain"
        candidates = [(a, b) for i, (a, pa) in enumerate(owned) for b, pb in owned[i + 1:]
                      if abs(pa - pb) >= 2]
        if not candidates:
            return "the URDF's collision geometry has no two bodies that can meet"
        geom.removeAllCollisionPairs()
        for a, b in candidates:
            geom.addCollisionPair(pin.CollisionPair(a, b))
        self._model, self._geom = model, geom
        self._chain_q = _config_map(model, chain_ids)
        self._set_margin()
        touching = self._touching_pairs_at(self._reference())
        self.disabled = [(geom.geometryObjects[a].name, geom.geometryObjects[b].name)
                         for k, (a, b) in enumerate(candidates) if touching[k]]
        geom.removeAllCollisionPairs()
        for k, (a, b) in enumerate(candidates):
            if not touching[k]:
                geom.addCollisionPair(pin.CollisionPair(a, b))
        self._set_margin()
        self._ngeoms, self._npairs = len({k for k, _ in owned}), len(geom.collisionPairs)
        self._pool = pin.GeometryPool(model, geom, max(1, self.threads))
        for data in self._pool.getGeometryDatas():  # the pool's own data, made without the margin
            for request in data.collisionRequests:
                request.security_margin = self.margin
        return ""

    def _set_margin(self) -> None:
        data = pin.GeometryData(self._geom)
        for request in data.collisionRequests:
            request.security_margin = self.margin
        self._geom_data = data

    def _configs(self, q: np.ndarray) -> np.ndarray:
        """(nq, N) pinocchio configurations of chain configurations `q` (N, dof); other joints neutral
        (a continuous joint is stored as cos, sin)."""
        neutral = pin.neutral(self._model)
        out = np.repeat(neutral[:, None], q.shape[0], axis=1)
        for column, (index, two) in enumerate(self._chain_q):
            if two:
                out[index], out[index + 1] = np.cos(q[:, column]), np.sin(q[:, column])
            else:
                out[index] = q[:, column]
        return out

    def _touching_pairs_at(self, q: np.ndarray) -> np.ndarray:
        """Which of the current pairs are in contact at the one configuration `q` (dof,)."""
        data = self._model.createData()
        config = self._configs(q[None])[:, 0]
        pin.computeCollisions(self._model, data, self._geom, self._geom_data, config, False)
        return np.array([r.isCollision() for r in self._geom_data.collisionResults], dtype=bool)

    def _reference(self) -> np.ndarray:
        lo, hi = self.chain.sampling_range()
        return (lo + hi) / 2.0

    # --- capsules --------------------------------------------------------------------------------------

    def _setup_capsules(self) -> None:
        self.radii = capsule_radii(self.chain)
        n = self.chain.dof + 1  # capsules: base→J1, J1→J2, …, JN→tip
        candidates = np.array([(i, j) for i in range(n) for j in range(i + 2, n)], dtype=int).reshape(-1, 2)
        touching = ~self._capsule_free(self._reference()[None], candidates)[0]
        self.disabled = [(f"capsule {a}", f"capsule {b}") for a, b in candidates[touching]]
        self._pairs = candidates[~touching]

    def _capsule_free(self, q: np.ndarray, pairs: np.ndarray) -> np.ndarray:
        """(N, P): whether each capsule pair keeps the sum of its radii + margin apart."""
        points = chain_frames(self.chain, q)[:, :, :3, 3]
        a, b = pairs[:, 0], pairs[:, 1]
        d = segment_distance(points[:, a], points[:, a + 1], points[:, b], points[:, b + 1])
        return d >= self.radii[a] + self.radii[b] + self.margin

    # --- the check ---------------------------------------------------------------------------------------

    def collides(self, q: np.ndarray) -> np.ndarray:
        """(N,) whether each configuration of `q` (N, dof) brings two checked bodies within `margin`."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        if q.shape[1] != self.chain.dof:
            raise ValueError(f"configurations of {q.shape[1]} joints for a chain of {self.chain.dof}")
        if self._pool is None:
            if len(self._pairs) == 0:
                return np.zeros(q.shape[0], dtype=bool)
            return ~np.all(self._capsule_free(q, self._pairs), axis=1)
        out = np.empty(q.shape[0], dtype=bool)
        for start in range(0, q.shape[0], BATCH):
            configs = np.asfortranarray(self._configs(q[start:start + BATCH]))
            out[start:start + BATCH] = pin.computeCollisionsInParallel(self.threads, self._pool, configs,
                                                                       True)
        return out

    def free(self, q: np.ndarray) -> np.ndarray:
        """(N,) the complement of `collides`."""
        return ~self.collides(q)


def _chain_positions(model: pin.Model, chain_ids: list[int], base_joint: int) -> dict[int, int | None]:
    """Each pinocchio joint's position on the chain: 0 for the base joint and its ancestors, i for chain
    joint i and the joints below it that are not on the chain (a hand's fingers below the last joint,
    held at their neutral value), None for joints on other branches."""
    position: dict[int, int | None] = {}
    ancestors = set()
    j = base_joint
    while True:
        ancestors.add(j)
        if j == 0:
            break
        j = model.parents[j]
    index = {jid: k + 1 for k, jid in enumerate(chain_ids)}
    for jid in range(model.njoints):
        if jid in ancestors:
            position[jid] = 0
            continue
        walk = jid
        while walk not in index and walk not in ancestors and walk != 0:
            walk = model.parents[walk]
        position[jid] = index.get(walk)  # a branch below a chain link, held neutral, moves with it
    return position


def _config_map(model: pin.Model, chain_ids: list[int]) -> list[tuple[int, bool]]:
    """Per chain joint: its first index in pinocchio's configuration and whether it takes two (cos, sin)."""
    return [(model.joints[j].idx_q, model.joints[j].nq == 2) for j in chain_ids]
