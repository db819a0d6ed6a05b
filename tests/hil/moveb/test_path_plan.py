"""The guarantees of issue 8, checked numerically on dense samples."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hil.moveb.bridge import ALPHA_G3, BridgeShape, bridge_derivatives, control_points
from hil.moveb.path_plan import Plan, plan_program
from hil.moveb.program import format_program, load_program, parse_program
from tests.hil.moveb.helpers import distance_to_polyline, point_errors

EXAMPLES = Path(__file__).parents[3] / "hil" / "moveb" / "examples"


def polyline(rng: np.random.Generator, n: int, max_turn_deg: float = 120.0, planar: bool = False
             ) -> np.ndarray:
    """A random path with segment lengths 5–40 mm and turns up to `max_turn_deg`."""
    d = np.array([1.0, 0.0, 0.0])
    pts = [np.zeros(3)]
    for _ in range(n - 1):
        axis = np.array([0, 0, 1.0]) if planar else rng.normal(size=3)
        axis -= (axis @ d) * d
        axis /= np.linalg.norm(axis)
        ang = np.radians(rng.uniform(-max_turn_deg, max_turn_deg))
        d = d * np.cos(ang) + np.cross(axis, d) * np.sin(ang)
        pts.append(pts[-1] + d * rng.uniform(5, 40))
    return np.array(pts)


def make_plan(P: np.ndarray, D: float | np.ndarray, E: float | np.ndarray, continuity: str) -> Plan:
    n = len(P)
    Z = np.tile([0.0, 0.0, -1.0], (n, 1))
    X = np.tile([1.0, 0.0, 0.0], (n, 1))
    return plan_program(parse_program(format_program(P, Z, X, D, E)), continuity)


def check_guarantees(plan: Plan) -> None:
    prog, curve = plan.program, plan.curve
    P, D, E = prog.positions, prog.d, prog.e
    # every original point within E of the curve
    assert np.all(point_errors(plan) <= E + 1e-9)
    # every corner's deviation (curve to the original polyline) within D of the nearest segment's points
    dense = plan.dense(0.05, per_bridge=200)
    dev, seg = distance_to_polyline(dense.position, P)
    assert np.all(dev <= np.maximum(D[seg], D[seg + 1]) + 1e-9)
    # no overlapping bridges: the straight pieces have non-negative length and the seed's inequality
    L = np.linalg.norm(np.diff(curve.working, axis=0), axis=1)
    arm = curve.shape.arm
    assert np.all(arm * (curve.h[:-1] + curve.h[1:]) <= L * (1 + 1e-12))
    assert np.all(curve._piece_len >= -1e-12)
    # the curve's ends are the program's ends
    assert np.allclose(dense.position[[0, -1]], P[[0, -1]], atol=1e-9)


def junctions(plan: Plan) -> np.ndarray:
    s = np.r_[plan.curve._s0, plan.curve.point_arclength()]
    return np.unique(s[(s > 1e-6) & (s < plan.length - 1e-6)])


def jumps(plan: Plan, key: str, eps: float = 1e-7) -> np.ndarray:
    s = junctions(plan)
    left, right = plan.curve.evaluate(s - eps), plan.curve.evaluate(s + eps)
    return np.abs(right[key] - left[key])


@pytest.mark.parametrize("continuity", ["G2", "G3"])
@pytest.mark.parametrize(("D", "E"), [(0.5, 0.2), (0.2, 0.5), (1.0, 0.02)])
def test_guarantees_on_random_paths(continuity: str, D: float, E: float) -> None:
    rng = np.random.default_rng(7)
    plan = make_plan(polyline(rng, 25), D, E, continuity)
    assert not plan.solution.fallback
    check_guarantees(plan)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), continuity=st.sampled_from(["G2", "G3"]),
       D=st.floats(0.05, 2.0), E=st.floats(0.01, 2.0))
def test_guarantees_property(seed: int, continuity: str, D: float, E: float) -> None:
    rng = np.random.default_rng(seed)
    check_guarantees(make_plan(polyline(rng, 8, max_turn_deg=150.0), D, E, continuity))


@pytest.mark.parametrize("continuity", ["G2", "G3"])
def test_groups_keep_their_own_thresholds(continuity: str) -> None:
    plan = plan_program(load_program(EXAMPLES / "square.moveb"), continuity)
    assert len(plan.program.groups()) == 2
    check_guarantees(plan)


@pytest.mark.parametrize("continuity", ["G2", "G3"])
def test_curvature_is_continuous(continuity: str) -> None:
    plan = make_plan(polyline(np.random.default_rng(3), 20), 0.5, 0.2, continuity)
    kmax = plan.dense(0.05).curvature.max()
    assert jumps(plan, "curvature").max() < 1e-4 * kmax
    # κ is zero where a bridge leaves a straight piece
    line = plan.curve.evaluate(plan.curve._s0 + plan.curve._piece_len / 2)
    assert np.all(line["curvature"][(plan.curve._kinds == 0) & (plan.curve._piece_len > 1e-9)] == 0.0)


def test_g3_has_a_continuous_curvature_derivative_and_g2_does_not() -> None:
    P = polyline(np.random.default_rng(4), 12)
    g2, g3 = make_plan(P, 0.5, 0.2, "G2"), make_plan(P, 0.5, 0.2, "G3")
    scale2 = np.abs(g2.dense(0.05).dcurvature).max()
    scale3 = np.abs(g3.dense(0.05).dcurvature).max()
    assert jumps(g3, "dcurvature", 1e-6).max() < 1e-3 * scale3
    assert jumps(g2, "dcurvature", 1e-6).max() > 0.5 * scale2  # the cubic's curvature has a kink at Q


def test_alpha_is_the_root_that_makes_the_apex_g3() -> None:
    assert pytest.approx(0.0, abs=1e-12) == 9 * ALPHA_G3 ** 2 - 5 * ALPHA_G3 - 2
    assert ALPHA_G3 >= 0.7
    shape = BridgeShape("G3")
    for turn in (10.0, 60.0, 120.0, 170.0):
        a = np.radians(turn)
        ctrl = control_points(np.zeros(3), np.array([1.0, 0, 0]), np.array([np.cos(a), np.sin(a), 0]),
                              np.array([2.0]), shape)
        from hil.moveb.bridge import curvature_terms

        u = np.array([0.5 - 1e-9, 0.5 + 1e-9])
        _, d1, d2, d3 = bridge_derivatives(np.repeat(ctrl, 2, axis=0), u, 4)
        k, dk = curvature_terms(d1, d2, d3)
        assert np.abs(dk).max() < 1e-6 * k.max() ** 2  # dκ/ds in units of κ²


@pytest.mark.parametrize("continuity", ["G2", "G3"])
def test_bezier_evaluation_matches_scipy_bspline(continuity: str) -> None:
    plan = make_plan(polyline(np.random.default_rng(5), 6), 0.5, 0.2, continuity)
    shape = plan.curve.shape
    for point in plan.curve.bridged:
        spline = plan.curve.bridge(int(point)).spline()
        ctrl = plan.curve.bridge(int(point)).control
        u = np.linspace(0.0, 1.0, 41)
        ours = bridge_derivatives(np.repeat(ctrl[None], len(u), axis=0), u, shape.degree)
        for nu in range(4):
            assert np.allclose(ours[nu], spline(u, nu=nu), atol=1e-9 * max(1.0, np.abs(ours[nu]).max()))


def test_straight_input_stays_straight() -> None:
    t = np.array([0.0, 7.0, 20.0, 21.5, 50.0])
    P = np.outer(t, [0.6, 0.0, 0.8]) + np.array([100.0, 20.0, 300.0])
    plan = make_plan(P, 0.5, 0.2, "G3")
    assert len(plan.curve.bridged) == 0
    dense = plan.dense(0.1)
    assert np.all(dense.curvature == 0.0)
    dev = np.linalg.norm(np.cross(dense.position - P[0], [0.6, 0.0, 0.8]), axis=1)
    assert dev.max() < 1e-12
    assert plan.length == pytest.approx(50.0, abs=1e-12)


def test_straight_parts_between_bridges_stay_on_the_working_lines() -> None:
    plan = make_plan(polyline(np.random.default_rng(6), 10), 0.3, 0.1, "G2")
    c = plan.curve
    lines = np.flatnonzero(c._kinds == 0)
    for frac in (0.25, 0.5, 0.75):
        ev = c.evaluate(c._s0[lines] + frac * c._piece_len[lines])
        W0, W1 = c.working[c._refs[lines]], c.working[c._refs[lines] + 1]
        d = (W1 - W0) / np.linalg.norm(W1 - W0, axis=1)[:, None]
        off = np.linalg.norm(np.cross(ev["position"] - W0, d), axis=1)
        assert off.max() < 1e-9


@pytest.mark.parametrize("continuity", ["G2", "G3"])
def test_frames_are_orthonormal_and_hit_the_program_axes(continuity: str) -> None:
    plan = plan_program(load_program(EXAMPLES / "weld_seam.moveb"), continuity)
    s = plan.dense(0.2)
    assert np.abs(np.linalg.norm(s.z_axis, axis=1) - 1).max() < 1e-12
    assert np.abs(np.linalg.norm(s.x_axis, axis=1) - 1).max() < 1e-12
    assert np.abs(np.einsum("ij,ij->i", s.z_axis, s.x_axis)).max() < 1e-12
    z, x = plan.frames(plan.s_keys)
    assert np.allclose(z, plan.program.z_axes, atol=1e-6)
    assert np.allclose(x, plan.program.x_axes, atol=1e-6)


def test_constant_orientation_stays_constant() -> None:
    plan = make_plan(polyline(np.random.default_rng(8), 10), 0.5, 0.2, "G3")
    s = plan.dense(0.5)
    assert np.abs(s.z_axis - [0, 0, -1]).max() < 1e-12
