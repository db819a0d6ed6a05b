"""The measured tool's model (`hil.arm.tool_frame`): its Jacobian against finite differences of the
model itself, the identifiable counts, and the model file's tool keys round trip."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from hil.arm import tool_frame as tf
from hil.arm.geometry import Geometry


@pytest.mark.parametrize(("reflectors", "orientation"), [(1, True), (3, False), (3, True)])
def test_the_jacobian_matches_finite_differences(reflectors: int, orientation: bool) -> None:
    g = tf.generic_tool("ur10e", reflectors, orientation)
    q = np.random.default_rng(0).uniform(-3, 3, (4, 6))
    _, _, J = tf.frame_and_jacobian(g, q, orientation)
    h = 1e-7
    numeric = np.zeros_like(J)
    for c in range(J.shape[2]):
        d = np.zeros(J.shape[2])
        d[c] = h
        pp, Rp = tf.predict(tf.apply_tool_update(g, d), q)
        pm, Rm = tf.predict(tf.apply_tool_update(g, -d), q)
        columns = [((pp - pm) / (2 * h)).reshape(len(q), -1)]
        if orientation:  # the model frame turned by ω: R' = exp(ω)·R
            columns.append(np.array([pin.log3(a @ b.T) for a, b in zip(Rp, Rm, strict=True)]) / (2 * h))
        numeric[:, :, c] = np.concatenate(columns, axis=1)
    assert np.max(np.abs(J - numeric)) < 1e-6 * np.max(np.abs(J))


@pytest.mark.parametrize(("reflectors", "orientation", "count"),
                         [(1, False, 27), (1, True, 30), (3, False, 33), (3, True, 36)])
def test_identifiable_counts(reflectors: int, orientation: bool, count: int) -> None:
    # positions identify 27 on a UR; orientations add the tool rotation (FIGAROH's 6-D UR10 fit has 30);
    # each further reflector its three offsets
    assert len(tf.identifiable_tool_parameters("ur10e", reflectors, orientation)) == count


def test_the_tool_keys_round_trip_and_old_files_read_without_them() -> None:
    g = tf.generic_tool("ur5e", 3, True)
    doc = g.to_dict()
    back = Geometry.from_dict(doc)
    assert np.allclose(back.tool_rotation, g.tool_rotation) and np.allclose(back.reflectors, g.reflectors)
    plain = {k: v for k, v in doc.items() if k not in ("tool_rpy", "reflectors")}
    old = Geometry.from_dict(plain)
    assert old.tool_rotation is None and old.reflectors is None
    np.testing.assert_allclose(tf.reflector_offsets(old), [g.smr])


def test_a_first_reflector_other_than_the_smr_is_refused() -> None:
    from hil.errors import InputError

    doc = tf.generic_tool("ur5e", 2, False).to_dict()
    doc["reflectors"][0] = [0.0, 0.0, 0.5]
    with pytest.raises(InputError, match=r"reflectors\[0\]"):
        Geometry.from_dict(doc, "m.json")
