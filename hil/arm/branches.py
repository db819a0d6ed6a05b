"""The nominal arm's configurations of a pose, as seeds: which branch the controller's IK would pick.

A UR arm reaches most poses in eight configurations (shoulder left/right, elbow up/down, wrist
flipped or not), and UR's controller picks among them the one nearest a joint vector ``qnear``
(``get_inverse_kin(pose, qnear)``; ``movej(p[...])`` uses the current joints). Damped least squares
(`hil.arm.ik`) converges to *some* solution from its seed, not necessarily the nearest one, so a
search for the nearest needs a seed on every branch: the closed-form IK of the *nominal* DH arm gives
them. They are only seeds — each is then solved on the real model (the controller's or hil's
calibrated chain, which have no closed form) by damped least squares, which stays on its seed's
branch; hil never moves by a closed form.

"Nearest" is UR's qnear sense: the largest single-joint difference, with every revolute joint taken
at the turn (±2π) nearest ``qnear`` that lies within the joint limits.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from hil.arm.catalog import ALPHA, RobotSpec, get_robot


def nominal_branches(robot: str | RobotSpec, flange: pin.SE3) -> list[np.ndarray]:
    """The (up to) eight configurations of the *nominal* DH arm putting its flange at `flange`.

    Only seeds (see the module docstring), each joint in [−π, π). The usual decomposition of UR's
    geometry (Hawkins, "Analytic inverse kinematics for the Universal Robots UR-5/UR-10 arms", 2013):
    joint 1 from the wrist centre's offset d4 from the base axis, joint 5 from the flange's, joint 6
    from the flange's orientation, then joints 2 and 3 as a planar two-link arm to frame 4 and joint 4
    from what is left. A pose out of the nominal arm's reach has none.

    Written out in scalars for UR's twists α = (π/2, 0, 0, π/2, −π/2, 0), which every arm of the
    catalog shares (`hil.arm.catalog.ALPHA`): it runs once per compensated target, and 4×4 matrix
    products in numpy cost ten times as much here.
    """
    spec = robot if isinstance(robot, RobotSpec) else get_robot(robot)
    if tuple(spec.dh.alpha) != ALPHA:
        raise ValueError(f"{spec.title}: the closed form assumes UR's twists {ALPHA}")
    d1, _, _, d4, d5, d6 = spec.dh.d
    a2, a3 = spec.dh.a[1], spec.dh.a[2]
    rows = pin.SE3(flange).homogeneous[:3].tolist()  # per base axis: the flange's x, y, z axes, origin
    (Xx, Yx, Zx, px), (Xy, Yy, Zy, py) = rows[:2]
    out: list[list[float]] = []
    # the wrist centre (frame 5's origin) lies d6 behind the flange along its z axis
    wx, wy = px - d6 * Zx, py - d6 * Zy
    r = math.hypot(wx, wy)
    if r <= abs(d4):
        return []
    psi, phi = math.atan2(wy, wx), math.acos(d4 / r)
    for s1 in (1.0, -1.0):
        t1 = psi + s1 * phi + math.pi / 2
        sin1, cos1 = math.sin(t1), math.cos(t1)
        c5 = (px * sin1 - py * cos1 - d4) / d6
        if abs(c5) > 1.0:
            continue
        for s5 in (1.0, -1.0):
            t5 = s5 * math.acos(c5)
            sin5 = math.sin(t5)
            t6 = 0.0 if abs(sin5) < 1e-9 else math.atan2((-Yx * sin1 + Yy * cos1) / sin5,
                                                        (Xx * sin1 - Xy * cos1) / sin5)
            sin6, cos6 = math.sin(t6), math.cos(t6)
            # frame 4 seen from frame 1 (A1⁻¹·T·(A5·A6)⁻¹): its x axis and its origin, both in the
            # plane of joints 2-4. In the flange frame that x axis is (c5c6, −c5s6, −s5) and the
            # origin (d5s6, d5c6, −d6); A1⁻¹ turns by −θ1 about z, drops d1 and turns by −π/2 about x.
            ex = [c5 * cos6 * X - c5 * sin6 * Y - sin5 * Z for X, Y, Z, _ in rows]
            o = [p + d5 * sin6 * X + d5 * cos6 * Y - d6 * Z for X, Y, Z, p in rows]
            t234 = math.atan2(ex[2], ex[0] * cos1 + ex[1] * sin1)
            x, y = o[0] * cos1 + o[1] * sin1, o[2] - d1
            c3 = (x * x + y * y - a2 * a2 - a3 * a3) / (2 * a2 * a3)
            if abs(c3) > 1.0:
                continue
            for s3 in (1.0, -1.0):
                t3 = s3 * math.acos(c3)
                t2 = math.atan2(y, x) - math.atan2(a3 * math.sin(t3), a2 + a3 * math.cos(t3))
                joints = (t1, t2, t3, t234 - t2 - t3, t5, t6)
                out.append([(t + math.pi) % (2 * math.pi) - math.pi for t in joints])
    return list(np.array(out))


def joint_distance(q: np.ndarray, near: np.ndarray) -> float:
    """UR's qnear distance of two joint vectors taken at their turns: the largest joint difference."""
    return float(np.max(np.abs(np.asarray(q, float) - np.asarray(near, float))))


def nearest_turns(q: np.ndarray, near: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """`q` (6, or N × 6) with each joint shifted by whole turns (2π) to lie nearest `near` within
    [lower, upper]; NaN where a joint has no turn within the limits.

    The same pose either way (a revolute joint repeats every turn): the controller, asked for a pose
    near `near`, takes the turn nearest it that its limits allow, so distances are measured there.
    """
    q, near = np.asarray(q, float), np.asarray(near, float)
    nearest = near + (q - near + np.pi) % (2 * np.pi) - np.pi
    other_side = nearest + np.where(nearest >= near, -2 * np.pi, 2 * np.pi)  # next nearest
    far_side = 2 * nearest - other_side  # a turn beyond the nearest, on its side
    out = np.full_like(nearest, np.nan)
    for candidate in (far_side, other_side, nearest):  # the nearest inside the limits wins
        out = np.where((candidate >= lower) & (candidate <= upper), candidate, out)
    return out


def other_branches_distance(robot: str | RobotSpec, flange: pin.SE3, q: np.ndarray,
                            near: np.ndarray) -> float:
    """A lower bound on how far from `near` (`joint_distance`) the nominal arm's configurations at
    `flange` lie, all but that of `q` (one solution of `flange`, at its turns nearest `near`).

    Why: a search for the configuration nearest `near` can stop at the solution seeded from `near`
    when every other configuration lies farther, and these three numbers tell it without computing
    any. Another configuration differs from q's by a flip of the shoulder, which takes joint 1 to
    2ψ + π − q1 (ψ the wrist centre's bearing: θ1 = ψ ± φ + π/2, Hawkins 2013); else, on the same
    shoulder, by a flip of the wrist, which takes joint 5 to −q5 (θ5 = ±acos of the same value); else by
    a flip of the elbow alone, which takes joint 3 to −q3 (the same planar two-link target). For a
    model near the nominal one (the controller's) the bound holds to the milliradians its solutions lie
    from the nominal configurations.
    """
    spec = robot if isinstance(robot, RobotSpec) else get_robot(robot)
    d6 = spec.dh.d[5]
    (_, _, zx, px), (_, _, zy, py) = pin.SE3(flange).homogeneous[:2].tolist()
    psi = math.atan2(py - d6 * zy, px - d6 * zx)
    q1, q3, q5 = float(q[0]), float(q[2]), float(q[4])
    flips = ((0, 2 * psi + math.pi - q1), (4, -q5), (2, -q3))
    return min(_turn_distance(value, float(near[j]), float(spec.lower[j]), float(spec.upper[j]))
               for j, value in flips)


def _turn_distance(value: float, near: float, lower: float, upper: float) -> float:
    """How far from `near` the turn of the angle `value` nearest it within [lower, upper] lies (inf:
    none within), in scalars: `nearest_turns` for one joint, called once per target."""
    nearest = near + (value - near + math.pi) % (2 * math.pi) - math.pi
    step = -2 * math.pi if nearest >= near else 2 * math.pi
    inside = [abs(v - near) for v in (nearest, nearest + step, nearest - step) if lower <= v <= upper]
    return min(inside, default=math.inf)


def branches_near(seeds: Sequence[np.ndarray], near: np.ndarray, robot: str | RobotSpec) -> np.ndarray:
    """(N, 6): the configurations `seeds` (e.g. `nominal_branches`) at their turns nearest `near`
    within the robot's limits (`nearest_turns`), nearest `near` first (`joint_distance`); a seed with
    a joint no turn brings within the limits is left out.

    The order is the one to try them in when looking for the controller's choice: once a solution is
    found, the seeds farther than it (by more than a solved seed moves from its nominal value) can be
    left unsolved.
    """
    if not len(seeds):
        return np.empty((0, 6))
    spec = robot if isinstance(robot, RobotSpec) else get_robot(robot)
    near = np.asarray(near, float)
    shifted = nearest_turns(np.asarray(seeds, float), near, spec.lower, spec.upper)
    shifted = shifted[~np.isnan(shifted).any(axis=1)]
    return shifted[np.argsort(np.abs(shifted - near).max(axis=1), kind="stable")]
