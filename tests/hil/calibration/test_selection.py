import numpy as np

from hil.arm.kinematics import Kinematics, identifiable_parameters
from hil.calibration.selection import SelectionModel


def test_frames_match_pinocchio() -> None:
    m = SelectionModel("ur10e", smr=(0.02, 0.01, 0.05), tracker=(3.0, -1.0, 0.2))
    q = np.random.default_rng(0).uniform(-np.pi, np.pi, size=(25, 6))
    assert np.allclose(m.frames(q), Kinematics(m.geometry).joint_frames(q), atol=1e-12)


def test_parameters_and_scales() -> None:
    off_axis = SelectionModel("ur5e", smr=(0.03, -0.02, 0.045))
    assert np.array_equal(off_axis.parameters, identifiable_parameters("ur5e"))
    assert off_axis.unobservable == []
    assert off_axis.parameter_scale.shape == (27,) and np.all(off_axis.parameter_scale > 0)
    on_axis = SelectionModel("ur5e", smr=(0.0, 0.0, 0.045))
    assert on_axis.unobservable and len(on_axis.parameters) == 27 - len(on_axis.unobservable)


def test_designing_for_joint_errors_spreads_the_joints_for_their_harmonics():
    """With the harmonics in the design, the chosen poses determine them better given the geometry: the
    geometric mean of their conditional information (the Schur complement of the geometry's block,
    columns scaled by the expected sizes) rises for every seed. The joints' angle ranges themselves are
    already covered by a geometric design (each joint visits 8-12 of twelve 30° sectors either way)."""
    from hil.calibration.selection import select_poses

    smr = (0.02, 0.03, 0.045)
    full = SelectionModel("ur5e", smr, joint_errors=(1, 2, 3))
    n_geo = len(SelectionModel("ur5e", smr).parameters)

    def harmonic_information(Q: np.ndarray) -> float:
        J = full.jacobian(Q).reshape(-1, len(full.parameters)) / full.parameter_scale
        M = J.T @ J
        A, B, C = M[:n_geo, :n_geo], M[:n_geo, n_geo:], M[n_geo:, n_geo:]
        return float(np.mean(np.log(np.linalg.eigvalsh(C - B.T @ np.linalg.solve(A, B)))))

    assert len(full.parameters) == n_geo + 36
    assert {"joint3.cos2", "joint6.sin3"} <= set(full.parameter_names)
    for seed in (0, 1):
        plain, designed = (np.array(select_poses("ur5e", 30, candidates=2000, method="exchange", seed=seed,
                                                 bound=False, smr=smr, joint_errors=orders)["poses"])
                           for orders in ((), (1, 2, 3)))
        assert harmonic_information(designed) > harmonic_information(plain) + np.log(1.3)
