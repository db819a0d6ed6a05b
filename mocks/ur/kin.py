"""Kinematic helpers for the simulated controller: pose vectors, a default nominal FK, numeric IK.

The controller simulator takes its forward kinematics as an injected callable ``q(6) -> 4x4`` (the
flange in the controller base frame), so one kinematic model — hil's — can serve every part of the
product. This module only provides a standard-DH fallback (the published UR nominal tables) so the
simulator runs without that model, plus what a controller needs around FK: UR pose vectors
``[x, y, z, rx, ry, rz]`` (rotation vector), TCP offsets and a damped least-squares IK.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

FkFn = Callable[[np.ndarray], np.ndarray]

# d1, a2, a3, d4, d5, d6 (metres), standard DH with alpha = [pi/2, 0, 0, pi/2, -pi/2, 0]
UR_DH: dict[str, tuple[float, float, float, float, float, float]] = {
    "ur3e": (0.15185, -0.24355, -0.2132, 0.13105, 0.08535, 0.0921),
    "ur5e": (0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996),
    "ur10e": (0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655),
    "ur16e": (0.1807, -0.4784, -0.36, 0.17415, 0.11985, 0.11655),
    "ur20": (0.2363, -0.862, -0.7287, 0.201, 0.1593, 0.1543),
    "ur30": (0.2363, -0.637, -0.5037, 0.201, 0.1593, 0.1543),
    "ur5": (0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823),
}
_ALPHA = np.array([np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0])


def dh_fk_factory(robot: str) -> FkFn:
    """Standard-DH nominal flange FK of a UR model (fallback when hil's model is not injected)."""
    try:
        d1, a2, a3, d4, d5, d6 = UR_DH[robot.lower()]
    except KeyError as exc:
        raise ValueError(f"unknown robot {robot!r}; known: {', '.join(sorted(UR_DH))}") from exc
    a = np.array([0.0, a2, a3, 0.0, 0.0, 0.0])
    d = np.array([d1, 0.0, 0.0, d4, d5, d6])
    ca, sa = np.cos(_ALPHA), np.sin(_ALPHA)

    def fk(q: np.ndarray) -> np.ndarray:
        T = np.eye(4)
        for i in range(6):
            ct, st = np.cos(q[i]), np.sin(q[i])
            A = np.array(
                [
                    [ct, -st * ca[i], st * sa[i], a[i] * ct],
                    [st, ct * ca[i], -ct * sa[i], a[i] * st],
                    [0.0, sa[i], ca[i], d[i]],
                    [0.0, 0.0, 0.0, 1.0],
                ]
            )
            T = T @ A
        return T

    return fk


def rotvec_to_matrix(r: np.ndarray) -> np.ndarray:
    """Rodrigues: rotation vector (axis * angle) to a 3x3 matrix."""
    r = np.asarray(r, dtype=float)
    th = float(np.linalg.norm(r))
    if th < 1e-12:
        return np.eye(3)
    k = r / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * (K @ K)


def matrix_to_rotvec(R: np.ndarray) -> np.ndarray:
    """Inverse Rodrigues, robust near 0 and pi (what UR reports as rx, ry, rz).

    Scalar arithmetic on the nine numbers: the controller runs this every 2 ms cycle.
    """
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R.tolist()
    cos_th = min(max((r00 + r11 + r22 - 1.0) / 2.0, -1.0), 1.0)
    th = math.acos(cos_th)
    wx, wy, wz = r21 - r12, r02 - r20, r10 - r01
    if th < 1e-9:
        return np.array([wx / 2.0, wy / 2.0, wz / 2.0])
    if math.pi - th < 1e-6:
        # axis from the symmetric part; sign is arbitrary at exactly pi
        B = (np.asarray(R, dtype=float) + np.eye(3)) / 2.0
        k = np.sqrt(np.clip(np.diag(B), 0.0, None))
        i = int(np.argmax(k))
        k = B[:, i] / np.sqrt(B[i, i])
        return k * th
    f = th / (2.0 * math.sin(th))
    return np.array([wx * f, wy * f, wz * f])


def pose_to_matrix(p: np.ndarray) -> np.ndarray:
    """UR pose vector [x, y, z, rx, ry, rz] to a 4x4 transform."""
    T = np.eye(4)
    T[:3, :3] = rotvec_to_matrix(np.asarray(p[3:6], dtype=float))
    T[:3, 3] = np.asarray(p[:3], dtype=float)
    return T


def matrix_to_pose(T: np.ndarray) -> np.ndarray:
    """4x4 transform to a UR pose vector."""
    return np.concatenate([T[:3, 3], matrix_to_rotvec(T[:3, :3])])


def pose_error(T_target: np.ndarray, T: np.ndarray) -> np.ndarray:
    """6-vector (translation, rotation vector) taking T to T_target, expressed in the base frame."""
    dp = T_target[:3, 3] - T[:3, 3]
    dR = T_target[:3, :3] @ T[:3, :3].T
    return np.concatenate([dp, matrix_to_rotvec(dR)])


def solve_ik(
    fk: FkFn,
    T_target: np.ndarray,
    q_seed: np.ndarray,
    *,
    tol_pos: float = 1e-9,
    tol_rot: float = 1e-9,
    max_iter: int = 60,
) -> np.ndarray | None:
    """Damped least-squares IK from a seed (the branch nearest the seed); None when it does not converge.

    Finite-difference Jacobians keep the solver independent of how the injected FK is built.
    """
    q = np.array(q_seed, dtype=float)
    h = 1e-7
    lam = 1e-6
    for _ in range(max_iter):
        T = fk(q)
        e = pose_error(T_target, T)
        if np.linalg.norm(e[:3]) < tol_pos and np.linalg.norm(e[3:]) < tol_rot:
            return q
        J = np.empty((6, 6))
        for j in range(6):
            dq = q.copy()
            dq[j] += h
            J[:, j] = pose_error(fk(dq), T) / h
        JT = J.T
        step = JT @ np.linalg.solve(J @ JT + lam * np.eye(6), e)
        n = float(np.linalg.norm(step))
        if n > 0.5:
            step *= 0.5 / n
        q = q + step
    T = fk(q)
    e = pose_error(T_target, T)
    if np.linalg.norm(e[:3]) < 1e-6 and np.linalg.norm(e[3:]) < 1e-6:
        return q
    return None


def nearest_equivalent(q: np.ndarray, q_ref: np.ndarray) -> np.ndarray:
    """Shift each joint by multiples of 2*pi to lie nearest the reference (same pose, shortest motion)."""
    return q_ref + (q - q_ref + np.pi) % (2 * np.pi) - np.pi
