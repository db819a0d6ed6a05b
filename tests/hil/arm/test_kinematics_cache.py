"""The per-geometry Kinematics cache: reused for equal content, rebuilt when the geometry changes in place,
one per thread, bounded; and the keep-in check that uses it sees a changed model at once."""

from __future__ import annotations

import threading

import numpy as np
import pinocchio as pin
import pytest

from hil.arm import kinematics_cache
from hil.arm.geometry import Geometry
from hil.arm.joint_errors import JointErrors
from hil.arm.kinematics import Kinematics
from hil.arm.kinematics_cache import CAPACITY, geometry_key, kinematics_of
from hil.arm.payload import Payload
from hil.arm.safety import check_target, path_fractions
from hil.errors import InputError

Q = np.random.default_rng(7).uniform(-2.0, 2.0, (5, 6))


@pytest.fixture(autouse=True)
def _empty_cache() -> None:
    kinematics_cache.clear()


def _geometry() -> Geometry:
    return Geometry.nominal("ur5e", smr=(0.0, 0.0, 0.045))


def test_equal_content_shares_one_model() -> None:
    g = _geometry()
    kin = kinematics_of(g)
    assert kinematics_of(g) is kin
    assert kinematics_of(_geometry()) is kin  # another object, same content
    np.testing.assert_array_equal(kin.points(Q), Kinematics(g).points(Q))


def _shift_smr(g: Geometry) -> None:
    g.smr[2] += 1e-6


def _shift_joint(g: Geometry) -> None:
    g.joints[2] = g.joints[2] * pin.SE3(np.eye(3), np.array([1e-6, 0.0, 0.0]))


def _turn_tracker(g: Geometry) -> None:
    g.tracker = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, 1e-6), np.zeros(3))


def _comply(g: Geometry) -> None:
    g.compliance = np.full(6, 1e-5)


def _carry(g: Geometry) -> None:
    g.compliance = np.full(6, 1e-5)
    kinematics_of(g)  # the compliant arm without a payload is cached first
    g.payload = Payload(3.0, (0.0, 0.0, 0.05))


def _joint_errors(g: Geometry) -> None:
    g.joint_errors = JointErrors.of([[[1, 1e-4, 0.0]]] + [[]] * 5)


def _lost_motion(g: Geometry) -> None:
    g.lost_motion = np.full(6, 1e-4)


def _tilt_gravity(g: Geometry) -> None:
    g.compliance = np.full(6, 1e-5)
    kinematics_of(g)
    g.gravity = np.array([0.0, -9.80665, 0.0])


@pytest.mark.parametrize("change", [_shift_smr, _shift_joint, _turn_tracker, _comply, _carry,
                                    _joint_errors, _lost_motion, _tilt_gravity])
def test_a_geometry_changed_in_place_gets_a_new_model(change) -> None:
    g = _geometry()
    before = kinematics_of(g)
    key = geometry_key(g)
    change(g)
    assert geometry_key(g) != key
    after = kinematics_of(g)
    assert after is not before
    D = np.ones((len(Q), 6))
    np.testing.assert_array_equal(after.points(Q, directions=D), Kinematics(g).points(Q, directions=D))
    assert not np.array_equal(after.points(Q, directions=D), before.points(Q, directions=D))


def test_the_cached_model_is_not_the_callers_object() -> None:
    """The model keeps a copy: changing the geometry afterwards cannot change a cached model."""
    g = _geometry()
    kin = kinematics_of(g)
    reference = kin.points(Q)
    g.smr[:] = 1.0
    np.testing.assert_array_equal(kinematics_of(_geometry()).points(Q), reference)


def test_each_thread_has_its_own_models() -> None:
    g = _geometry()
    here = kinematics_of(g)
    there: list[Kinematics] = []
    worker = threading.Thread(target=lambda: there.extend([kinematics_of(g), kinematics_of(g)]))
    worker.start()
    worker.join()
    assert there[0] is there[1]  # cached in that thread
    assert there[0] is not here and there[0].data is not here.data  # pinocchio Data is not shared


def test_the_least_recently_used_model_is_dropped_beyond_capacity() -> None:
    geometries = [Geometry.nominal("ur5e", smr=(0.0, 0.0, 0.01 * k)) for k in range(CAPACITY + 1)]
    first = kinematics_of(geometries[0])
    kept = kinematics_of(geometries[1])
    for g in geometries[2:CAPACITY]:
        kinematics_of(g)
    assert kinematics_of(geometries[0]) is first  # used again: now the most recent
    kinematics_of(geometries[CAPACITY])  # one too many: geometries[1] is the oldest
    assert kinematics_of(geometries[0]) is first
    assert kinematics_of(geometries[1]) is not kept


def test_check_target_sees_a_model_changed_after_a_check() -> None:
    """The keep-in check of the same model object refuses once its SMR moves the point out of the box."""
    g = _geometry()
    q = np.array([0.0, -1.2, 1.0, -1.4, -1.57, 0.0])
    p = Kinematics(g).points(q, frame="base")[0]
    box = (p - 0.01, p + 0.01)
    check_target(q, g.spec, box, g)
    g.smr[2] += 0.05
    with pytest.raises(InputError, match="outside the keep-in box"):
        check_target(q, g.spec, box, g)


def test_check_target_path_points_are_the_straight_joint_path() -> None:
    """The path check evaluates start + s·(q − start) at `path_checks` evenly spaced s, ends included,
    and at the driver's (`path_fractions`): a box around those points only passes, a box missing the
    middle ones refuses."""
    g = _geometry()
    start = np.array([-1.5, -1.2, 1.0, -1.4, -1.57, 0.0])
    q = start + np.array([3.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # the base swings the SMR round an arc
    s = path_fractions(3)
    pts = Kinematics(g).points([start + (q - start) * k for k in s], frame="base")
    check_target(q, g.spec, (pts.min(0) - 1e-9, pts.max(0) + 1e-9), g, start, path_checks=3)
    ends = pts[[0, -1]]
    middle = pts[len(pts) // 2]
    assert not np.all((middle >= ends.min(0)) & (middle <= ends.max(0)))  # the arc bulges out
    with pytest.raises(InputError, match="path to the target"):
        check_target(q, g.spec, (ends.min(0) - 1e-9, ends.max(0) + 1e-9), g, start, path_checks=3)
