"""The joint-error and lost-motion parameters: their Jacobian columns, updates and identifiability."""

from __future__ import annotations

import numpy as np
import pytest

from hil.arm.joint_error_columns import (
    LOST_MOTION_SLICE,
    MAX_FIT_ORDER,
    harmonic_index,
    lost_motion_index,
    term_groups,
)
from hil.arm.joint_errors import JointErrors
from hil.arm.kinematics import (
    EXTENDED_PARAMETER_NAMES,
    JOINT_ERROR_SLICE,
    N_ALL_PARAMETERS,
    N_EXTENDED_PARAMETERS,
    N_PARAMETERS,
    Kinematics,
    apply_update,
    deviation_from,
    generic_configurations,
    generic_geometry,
    identifiable_joint_errors,
    identifiable_parameters,
)


@pytest.fixture
def arm(rng):
    """A generic arm that already carries compliance, a few harmonics and lost motion: the columns must
    hold away from the nominal too."""
    g = apply_update(generic_geometry("ur5e"), rng.normal(0, 1e-3, N_PARAMETERS))
    g.compliance = np.full(6, 2e-6)
    g.joint_errors = JointErrors.of([[[1, 1e-4, -2e-4], [7, 3e-5, 0.0]], [], [[2, 5e-5, 5e-5]], [], [], []])
    g.lost_motion = np.full(6, 4e-5)
    return g


def test_names_follow_the_layout():
    assert EXTENDED_PARAMETER_NAMES[harmonic_index(2, 2, "cos")] == "joint3.cos2"
    assert EXTENDED_PARAMETER_NAMES[harmonic_index(2, 2, "sin")] == "joint3.sin2"
    assert EXTENDED_PARAMETER_NAMES[lost_motion_index(2)] == "lost_motion.j3"
    assert N_EXTENDED_PARAMETERS == N_ALL_PARAMETERS + 6 * MAX_FIT_ORDER * 2 + 6
    assert len(term_groups()) == 6 * MAX_FIT_ORDER + 6


def test_harmonic_and_lost_motion_columns_agree_with_finite_differences(arm, rng):
    Q = rng.uniform(-np.pi, np.pi, (6, 6))
    D = rng.choice([-1.0, 1.0], (6, 6))
    p, J = Kinematics(arm).point_and_jacobian(Q, True, D, True)
    assert J.shape == (6, 3, N_EXTENDED_PARAMETERS)
    assert np.allclose(p, Kinematics(arm).points(Q, directions=D))
    h = 1e-7
    for i in range(N_ALL_PARAMETERS, N_EXTENDED_PARAMETERS):
        step = np.zeros(N_EXTENDED_PARAMETERS)
        step[i] = h
        fd = (Kinematics(apply_update(arm, step)).points(Q, directions=D)
              - Kinematics(apply_update(arm, -step)).points(Q, directions=D)) / (2 * h)
        scale = np.abs(J[:, :, i]).max()
        assert scale > 1e-2, EXTENDED_PARAMETER_NAMES[i]  # m/rad: every column moves the point
        assert np.abs(fd - J[:, :, i]).max() <= 1e-6 * scale, EXTENDED_PARAMETER_NAMES[i]


def test_the_geometric_columns_do_not_change_with_the_extension(arm, rng):
    Q = rng.uniform(-np.pi, np.pi, (4, 6))
    _, J57 = Kinematics(arm).point_and_jacobian(Q, True)
    _, J99 = Kinematics(arm).point_and_jacobian(Q, True, None, True)
    assert np.array_equal(J57, J99[:, :, :N_ALL_PARAMETERS])
    assert not np.any(J99[:, :, LOST_MOTION_SLICE])  # no directions: nothing to lag by


def test_update_and_deviation_are_inverse_for_the_joint_errors(arm, rng):
    delta = rng.normal(0, 1e-4, N_EXTENDED_PARAMETERS)
    moved = apply_update(arm, delta)
    assert np.allclose(deviation_from(arm, moved, True, True), delta, atol=1e-12)
    # terms beyond the fitted orders stay as they were; fitted ones add up
    assert any(h.order == 7 and h.cos == 3e-5 for h in moved.joint_errors.joints[0])
    first = {h.order: h for h in moved.joint_errors.joints[0]}[1]
    assert first.cos == pytest.approx(1e-4 + delta[harmonic_index(0, 1, "cos")], abs=1e-15)
    assert np.allclose(moved.lost_motion, arm.lost_motion + delta[LOST_MOTION_SLICE])


def test_a_step_without_joint_errors_leaves_the_blocks_absent():
    g = generic_geometry("ur5e")
    moved = apply_update(g, np.r_[np.full(N_ALL_PARAMETERS, 1e-6), np.zeros(N_EXTENDED_PARAMETERS - 57)])
    assert moved.joint_errors is None and moved.lost_motion is None


@pytest.mark.parametrize("robot", ["ur5e", "ur10e", "ur3"])
def test_every_low_order_term_is_independent_of_the_geometry(robot):
    """The finding `identifiable_joint_errors` documents: orders 1-3 and lost motion all independent."""
    found = identifiable_joint_errors(robot)
    assert found.tolist() == list(range(N_ALL_PARAMETERS, N_EXTENDED_PARAMETERS))
    assert identifiable_joint_errors(robot, compliance=True).tolist() == found.tolist()


def test_lost_motion_approached_from_one_side_is_the_joints_offset():
    """Why lost motion is offered only where the directions vary: one-sided, it is a constant."""
    g = generic_geometry("ur5e")
    Q = generic_configurations("ur5e")
    J = Kinematics(g).jacobian(Q, np.arange(N_EXTENDED_PARAMETERS), np.ones_like(Q))
    J = J.reshape(-1, N_EXTENDED_PARAMETERS)
    base = J[:, identifiable_parameters("ur5e")]
    basis, _ = np.linalg.qr(base / np.linalg.norm(base, axis=0))
    for i in range(LOST_MOTION_SLICE.start, LOST_MOTION_SLICE.stop):
        c = J[:, i] / np.linalg.norm(J[:, i])
        assert np.linalg.norm(c - basis @ (basis.T @ c)) < 1e-7, EXTENDED_PARAMETER_NAMES[i]
    harmonic = J[:, JOINT_ERROR_SLICE][:, 0]  # joint1.cos1 is not
    c = harmonic / np.linalg.norm(harmonic)
    assert np.linalg.norm(c - basis @ (basis.T @ c)) > 0.5
