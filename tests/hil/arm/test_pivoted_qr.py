"""hil's pivoted QR against LAPACK's (scipy.linalg.qr with pivoting): the same columns, in the same
order, with the same diagonal, on the identification Jacobians it serves and on rank-deficient ones."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from hil.arm.catalog import ROBOT_NAMES
from hil.arm.kinematics import (
    _GROUP_ORDER,
    N_ALL_PARAMETERS,
    N_PARAMETERS,
    Kinematics,
    generic_configurations,
    generic_geometry,
    identifiable_parameters,
    identifiable_with_compliance,
    numerical_rank,
    select_identifiable,
)
from hil.arm.payload import Payload
from hil.arm.pivoted_qr import pivoted_qr


def lapack(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    q, r, piv = scipy.linalg.qr(A, mode="economic", pivoting=True)
    return q, np.abs(np.diag(r)), piv


def lapack_select(J: np.ndarray, tol: float = 1e-7) -> np.ndarray:
    """`select_identifiable` as it was written on scipy's pivoted QR."""
    norms = np.linalg.norm(J, axis=0)
    Js = J / np.where(norms > 0, norms, 1.0)
    basis = np.zeros((J.shape[0], 0))
    chosen: list[int] = []
    groups = _GROUP_ORDER + ((slice(51, 57),) if J.shape[1] > N_PARAMETERS else ())
    for group in groups:
        idx = np.arange(J.shape[1])[group]
        cols = Js[:, idx] - basis @ (basis.T @ Js[:, idx])
        cols[:, norms[idx] == 0] = 0.0
        q, d, piv = lapack(cols)
        k = int(np.sum(d > tol))
        chosen.extend(int(i) for i in idx[piv[:k]])
        basis = np.hstack([basis, q[:, :k]])
    return np.array(sorted(chosen), dtype=int)


@pytest.mark.parametrize("shape", [(30, 8), (8, 30), (120, 27), (5, 5)])
def test_a_full_rank_matrix_factorises_as_lapack_does(shape: tuple[int, int]) -> None:
    A = np.random.default_rng(sum(shape)).normal(size=shape) * np.geomspace(1, 1e3, shape[1])
    Q, d, piv = pivoted_qr(A)
    _, d_ref, piv_ref = lapack(A)
    assert np.array_equal(piv[: len(d)], piv_ref[: len(d)])
    assert np.allclose(d, d_ref, rtol=1e-10)
    assert np.allclose(Q.T @ Q, np.eye(Q.shape[1]), atol=1e-13)
    R = Q.T @ A[:, piv]
    assert np.allclose(Q @ R, A[:, piv], atol=1e-10 * np.abs(A).max())
    assert np.allclose(np.abs(np.diag(R)), d, rtol=1e-10)


def test_a_rank_deficient_matrix_shows_its_rank_on_the_diagonal() -> None:
    rng = np.random.default_rng(5)
    B = rng.normal(size=(40, 4))
    A = np.c_[B, B @ rng.normal(size=(4, 3)), np.zeros((40, 1))]  # rank 4 of 8
    d = pivoted_qr(A)[1]
    d_ref = lapack(A)[1]
    assert np.sum(d > 1e-10 * d[0]) == np.sum(d_ref > 1e-10 * d_ref[0]) == 4
    assert np.allclose(d[:4], d_ref[:4], rtol=1e-10)


@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_the_identifiable_sets_are_lapacks(robot: str) -> None:
    g = generic_geometry(robot)
    J = Kinematics(g).jacobian(generic_configurations(robot)).reshape(-1, N_PARAMETERS)
    assert np.array_equal(identifiable_parameters(robot), lapack_select(J))
    assert np.array_equal(select_identifiable(J), lapack_select(J))
    payload = Payload(3.0, (0.0, 0.0, 0.05))
    g.payload = payload
    Jc = Kinematics(g).jacobian(generic_configurations(robot), np.arange(N_ALL_PARAMETERS))
    chosen = identifiable_with_compliance(robot, payload)
    assert len(chosen) > 27
    assert set(identifiable_parameters(robot)) <= set(chosen)
    assert np.array_equal(select_identifiable(Jc.reshape(-1, N_ALL_PARAMETERS)),
                          lapack_select(Jc.reshape(-1, N_ALL_PARAMETERS)))


def test_the_rank_of_an_arm_with_the_smr_on_its_last_axis() -> None:
    on_axis = generic_geometry("ur5e")
    on_axis.smr = np.array([0.0, 0.0, 0.05])
    J = Kinematics(on_axis).jacobian(generic_configurations("ur5e")).reshape(-1, N_PARAMETERS)
    norms = np.linalg.norm(J, axis=0)
    d_ref = lapack(J[:, norms > 0] / norms[norms > 0])[1]
    assert numerical_rank(J) == int(np.sum(d_ref > 1e-7 * d_ref[0])) == 26
