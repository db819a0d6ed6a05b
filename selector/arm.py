"""The arm as capsules, and the singularity measures of the UR structure, from batched joint frames.

Input everywhere is `frames` (N, 7, 4, 4): the six joint frames after their rotation and the flange, in
the robot base frame (what `PoseModel.frames` returns; the URDF layout of ``ur_description``). Another
serial arm (n joints, frames (N, n + 1, 4, 4)) is `ChainShape`: capsules between its frame origins, and
no singularity measures (they are the UR structure's).

**Where the links really are.** The DH frames of joints 2–4 lie in one plane, but the physical arm
does not: the upper arm runs beside the shoulder, offset along the joint-2 axis, and the forearm comes
back, so that the wrist ends up d4 from the plane of joint 2 (d4 = shoulder offset − elbow offset +
wrist-1 offset; for a UR5e 0.138 − 0.131 + 0.127 ≈ 0.1333). The capsules therefore follow the
physical chain, with the upper arm displaced by ``shoulder_offset``·d4 along the joint-2 axis (the
actual shoulder offset is within a few millimetres of d4 on every e-series arm) and the forearm in the
DH plane:

    base      base origin → joint 1            shoulder  joint 2 → joint 2 + s·z2
    upper_arm joint 2 + s·z2 → joint 3 + s·z2  elbow     joint 3 + s·z2 → joint 3
    forearm   joint 3 → joint 4 − d4·z4        wrist1    joint 4 − d4·z4 → joint 4
    wrist2    joint 4 → joint 5                wrist3    joint 5 → joint 6 (the flange)
    tool      flange → SMR centre

Radii are a UR5e's housings (generous by a few millimetres) multiplied by the model's ``link_scale``.
Self-collision checks capsule pairs at least three apart in this chain (closer ones touch by
construction); the floor check skips the base and shoulder, which stand on it.

**Singularities** (UR: three parallel middle joints, non-spherical wrist):

* wrist — joints 4 and 6 parallel: |z4 × z6| = |sin q5|;
* elbow — arm stretched or folded: |x2 × x3| = |sin q3| (x2, x3 run along the upper arm, forearm);
* shoulder — the wrist point (joint 5's origin, where the analytic IK's two shoulder branches meet)
  on the plane of the joint-1 and joint-2 axes: its distance from that plane, in metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

CAPSULE_NAMES: tuple[str, ...] = (
    "base", "shoulder", "upper_arm", "elbow", "forearm", "wrist1", "wrist2", "wrist3", "tool",
)
#: UR5e housing radii (m) per capsule, with a few millimetres of margin.
UR5E_RADII: tuple[float, ...] = (0.080, 0.080, 0.060, 0.065, 0.050, 0.048, 0.048, 0.048, 0.025)
#: Clearance (m) two capsules keep beyond their radii for a posture to count as free of self-collision.
COLLISION_MARGIN = 0.01


@dataclass(frozen=True)
class ArmShape:
    """Capsule radii and the physical shoulder offset (as a multiple of the DH d4)."""

    radii: tuple[float, ...] = UR5E_RADII
    shoulder_offset: float = 1.0
    #: Capsules before this index stand on the mounting surface (base, shoulder): the floor skips them.
    floor_from: int = 2
    #: The wrist/elbow/shoulder measures below are defined on this layout.
    ur_singularities: bool = True

    @classmethod
    def scaled(cls, factor: float) -> ArmShape:
        """A UR5e's capsules scaled by `factor` (the link thicknesses grow with the arm)."""
        return cls(tuple(r * factor if name != "tool" else r
                         for r, name in zip(UR5E_RADII, CAPSULE_NAMES, strict=True)))

    def segments(self, frames: np.ndarray, smr_base: np.ndarray) -> np.ndarray:
        """(N, 9, 2, 3) capsule end points in the base frame (see module docstring)."""
        F = np.asarray(frames, dtype=float)
        o = F[:, :, :3, 3]  # origins (N, 7, 3)
        z = F[:, :, :3, 2]  # z axes
        J2, J3, J4, J5, J6 = o[:, 1], o[:, 2], o[:, 3], o[:, 4], o[:, 5]
        d4 = np.einsum("ni,ni->n", J4 - J3, z[:, 2])[:, None] * z[:, 2]  # the d4 offset vector
        s = self.shoulder_offset * d4
        wrist1_start = J4 - d4
        base0 = np.zeros_like(J2)
        ends = [
            (base0, o[:, 0]), (J2, J2 + s), (J2 + s, J3 + s), (J3 + s, J3), (J3, wrist1_start),
            (wrist1_start, J4), (J4, J5), (J5, J6), (F[:, 6, :3, 3], smr_base),
        ]
        return np.stack([np.stack(e, axis=1) for e in ends], axis=1)

    @property
    def collision_pairs(self) -> np.ndarray:
        """(P, 2) capsule index pairs checked for self-collision: at least three apart in the chain."""
        n = len(CAPSULE_NAMES)
        return np.array([(i, j) for i in range(n) for j in range(i + 3, n)])

    def collision_free(self, segments: np.ndarray, margin: float = COLLISION_MARGIN) -> np.ndarray:
        """(N,) whether no two capsules of `collision_pairs` come closer than `margin` (surface to
        surface), for capsule end points `segments` (N, 9, 2, 3) from `segments`."""
        radii = np.asarray(self.radii)
        pairs = self.collision_pairs
        a, b = segments[:, pairs[:, 0]], segments[:, pairs[:, 1]]
        d = segment_distance(a[:, :, 0], a[:, :, 1], b[:, :, 0], b[:, :, 1])
        return np.all(d >= radii[pairs[:, 0]] + radii[pairs[:, 1]] + margin, axis=1)


@dataclass(frozen=True)
class ChainShape:
    """Capsules of any serial chain from its joint frames (N, n + 1, 4, 4) (n joints and the flange):
    base origin → joint 1's origin, joint i → joint i + 1, joint n → the flange, and the tool (flange →
    SMR centre), n + 2 capsules. Without a UR's physical layout to follow, the capsules run between the
    frame origins; `radii` (one per capsule), the checked `pairs` and `floor_from` come from the caller,
    who knows the arm (hil sizes them from its chain). The UR singularity measures do not apply.
    """

    radii: tuple[float, ...]
    pairs: tuple[tuple[int, int], ...]
    floor_from: int = 1
    ur_singularities: bool = False

    def segments(self, frames: np.ndarray, smr_base: np.ndarray) -> np.ndarray:
        """(N, n + 2, 2, 3) capsule end points in the base frame."""
        o = np.asarray(frames, dtype=float)[:, :, :3, 3]
        points = np.concatenate([np.zeros_like(o[:, :1]), o, np.asarray(smr_base, float)[:, None]], axis=1)
        return np.stack([points[:, :-1], points[:, 1:]], axis=2)

    @property
    def collision_pairs(self) -> np.ndarray:
        """(P, 2) capsule index pairs checked for self-collision."""
        return np.asarray(self.pairs, dtype=int).reshape(-1, 2)

    def collision_free(self, segments: np.ndarray, margin: float = COLLISION_MARGIN) -> np.ndarray:
        """(N,) whether no pair of `collision_pairs` comes closer than `margin` (surface to surface)."""
        pairs = self.collision_pairs
        if len(pairs) == 0:
            return np.ones(len(segments), dtype=bool)
        radii = np.asarray(self.radii)
        a, b = segments[:, pairs[:, 0]], segments[:, pairs[:, 1]]
        d = segment_distance(a[:, :, 0], a[:, :, 1], b[:, :, 0], b[:, :, 1])
        return np.all(d >= radii[pairs[:, 0]] + radii[pairs[:, 1]] + margin, axis=1)


def segment_distance(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """Distance between segments p1q1 and p2q2, batched over leading axes (Ericson, RTCD 5.1.9)."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a = np.einsum("...i,...i->...", d1, d1)
    e = np.einsum("...i,...i->...", d2, d2)
    f = np.einsum("...i,...i->...", d2, r)
    c = np.einsum("...i,...i->...", d1, r)
    b = np.einsum("...i,...i->...", d1, d2)
    eps = 1e-12
    a_ok, e_ok = a > eps, e > eps
    a_safe, e_safe = np.where(a_ok, a, 1.0), np.where(e_ok, e, 1.0)
    denom = a * e - b * b
    # General case: closest points of the infinite lines, s clamped (s = 0 for parallel lines).
    s = np.where(denom > eps * a_safe * e_safe, np.clip((b * f - c * e) / np.where(denom > 0, denom, 1.0),
                                                        0.0, 1.0), 0.0)
    t = (b * s + f) / e_safe
    # t outside [0, 1]: clamp it and recompute s for the clamped t.
    s_low, s_high = np.clip(-c / a_safe, 0.0, 1.0), np.clip((b - c) / a_safe, 0.0, 1.0)
    s = np.where(t < 0.0, s_low, np.where(t > 1.0, s_high, s))
    t = np.clip(t, 0.0, 1.0)
    # Degenerate segments (points).
    s = np.where(~e_ok, np.clip(-c / a_safe, 0.0, 1.0), s)
    t = np.where(~e_ok, 0.0, t)
    t = np.where(~a_ok, np.clip(f / e_safe, 0.0, 1.0), t)
    s = np.where(~a_ok, 0.0, s)
    c1 = p1 + d1 * s[..., None]
    c2 = p2 + d2 * t[..., None]
    return np.linalg.norm(c1 - c2, axis=-1)


def point_segment_distance(x: np.ndarray, p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Distance from points x to segments pq, batched over leading axes."""
    d = q - p
    dd = np.einsum("...i,...i->...", d, d)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(np.einsum("...i,...i->...", x - p, d) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    return np.linalg.norm(x - (p + d * t[..., None]), axis=-1)


def wrist_measure(frames: np.ndarray) -> np.ndarray:
    """|sin q5|: 0 at the wrist singularity (joint 4 and joint 6 axes parallel)."""
    return np.linalg.norm(np.cross(frames[:, 3, :3, 2], frames[:, 5, :3, 2]), axis=-1)


def elbow_measure(frames: np.ndarray) -> np.ndarray:
    """|sin q3|: 0 when the arm is stretched or folded (upper arm and forearm aligned)."""
    return np.linalg.norm(np.cross(frames[:, 1, :3, 0], frames[:, 2, :3, 0]), axis=-1)


def shoulder_measure(frames: np.ndarray) -> np.ndarray:
    """Distance (m) of the wrist point from the plane of the joint-1 and joint-2 axes."""
    z1, z2 = frames[:, 0, :3, 2], frames[:, 1, :3, 2]
    normal = np.cross(z1, z2)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    w = frames[:, 4, :3, 3] - frames[:, 0, :3, 3]
    return np.abs(np.einsum("ni,ni->n", w, normal))
