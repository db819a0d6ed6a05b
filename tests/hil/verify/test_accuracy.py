"""ISO 9283 AP and RP against a computation by hand (ISO 9283:1998 §7.2.1, §7.2.2)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hil.verify.accuracy import pose_accuracy


def test_ap_and_rp_of_four_made_up_points_match_the_hand_computation() -> None:
    # four attained positions (mm) of a pose commanded at (1, 2, 3) mm
    attained = np.array([[1.0, 2.0, 3.0], [3.0, 2.0, 3.0], [2.0, 4.0, 3.0], [2.0, 2.0, 7.0]]) * 1e-3
    commanded = np.array([1.0, 2.0, 3.0]) * 1e-3
    acc = pose_accuracy(attained, commanded)
    # barycentre (8/4, 10/4, 16/4) = (2, 2.5, 4) mm
    assert acc.barycentre == pytest.approx(np.array([2.0, 2.5, 4.0]) * 1e-3)
    # AP_x = 2 − 1 = 1, AP_y = 2.5 − 2 = 0.5, AP_z = 4 − 3 = 1; AP_P = √(1 + 0.25 + 1) = 1.5 mm
    assert acc.ap == pytest.approx(np.array([1.0, 0.5, 1.0]) * 1e-3)
    assert acc.ap_p == pytest.approx(1.5e-3)
    # l_j: |(−1, −0.5, −1)| = 1.5, |(1, −0.5, −1)| = 1.5, |(0, 1.5, −1)| = √3.25, |(0, −0.5, 3)| = √9.25
    dist = np.array([1.5, 1.5, math.sqrt(3.25), math.sqrt(9.25)])
    l_mean = (3.0 + math.sqrt(3.25) + math.sqrt(9.25)) / 4
    s_l = math.sqrt(sum((x - l_mean) ** 2 for x in dist) / 3)  # n − 1 = 3
    assert acc.l_mean == pytest.approx(l_mean * 1e-3)
    assert acc.s_l == pytest.approx(s_l * 1e-3)
    assert acc.rp_l == pytest.approx((l_mean + 3 * s_l) * 1e-3)
    # by hand: l̄ = 7.84416 / 4; deviations −0.46104 (twice), −0.15826, 1.08034; squares sum 1.61731
    assert (round(l_mean, 4), round(s_l, 4), round(l_mean + 3 * s_l, 4)) == (1.961, 0.7342, 4.1637)
    d = acc.as_dict()
    assert d["AP_P"] == pytest.approx(1.5e-3) and d["RP_l"] == pytest.approx(4.1637e-3, abs=1e-7)


def test_ap_components_are_turned_into_the_base_frame() -> None:
    """The tracker measures in its own frame; AP_x/y/z are along the base axes (here the tracker is
    turned 90° about z: its x axis is the base's y axis)."""
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # tracker axes in the base frame
    attained = np.array([[1e-3, 0.0, 0.0], [1e-3, 0.0, 0.0]])
    acc = pose_accuracy(attained, np.zeros(3), to_base=turn)
    assert acc.ap == pytest.approx([0.0, 1e-3, 0.0])
    assert acc.ap_p == pytest.approx(1e-3) and acc.rp_l == pytest.approx(0.0)


def test_repeatability_needs_two_points() -> None:
    with pytest.raises(ValueError, match="at least 2"):
        pose_accuracy(np.zeros((1, 3)), np.zeros(3))
