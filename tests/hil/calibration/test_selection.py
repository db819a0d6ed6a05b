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
