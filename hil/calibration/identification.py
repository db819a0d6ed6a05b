"""Kinematic parameter identification from SMR positions measured by a tracker.

The fit is a Levenberg–Marquardt loop written here rather than ``scipy.optimize.least_squares``
because the step must be applied *multiplicatively* on SE(3) (`kinematics.apply_update`): scipy only
adds steps to a vector, and an additive update of the twist with the Jacobian taken at zero error
converges to a biased answer. Everything else comes from libraries: pinocchio for the kinematics,
numpy for the linear algebra (the Kabsch alignment is one 3 × 3 SVD; the pivoted QR is
`hil.arm.pivoted_qr`), and the F distribution's tail from `hil.calibration.distributions` — scipy's
import was most of ``hil identify``'s start-up.

Steps:
1. check the data can identify the parameters at all (pose count, joints that never move, rank);
2. align the tracker frame in closed form (Kabsch fit of nominal SMR positions to measured ones),
   so the user supplies only the robot type and optionally a rough SMR offset;
3. fit the tracker pose and SMR offset alone, then all identifiable parameters (27 for a UR);
4. reject outliers one at a time by a leave-one-out F test on each pose's leverage-corrected
   residual (Bonferroni at α = 1 %), refitting after each rejection; the rejected poses are named;
5. unless told not to, refit with the robot's manufacturing tolerances as a Gaussian prior
   (`hil.calibration.prior`: a maximum-a-posteriori fit, extra residual rows in the same LM step), the
   prior's weight σ²/τ² taken from the noise the fit finds (σ̂ and the weights iterated to agreement),
   so few or noisy poses shrink toward nominal; outliers are judged by the plain least-squares fit
   before it, so the prior cannot hide one;
6. report the fit RMS/max, iterations, condition number, covariance, standard deviations and
   strongly correlated parameter pairs.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hil.arm.chain import Robot, chain_of, robot_name
from hil.arm.geometry import Geometry
from hil.arm.kinematics import (
    EXTENDED_PARAMETER_NAMES,
    N_ALL_PARAMETERS,
    N_PARAMETERS,
    Kinematics,
    apply_update,
    deviation_from,
    generic_geometry,
    identifiable_parameters,
    identifiable_with_compliance,
    numerical_rank,
    parameter_layout,
    parameter_names,
    refuse_non_ur,
)
from hil.arm.payload import Payload
from hil.arm.pivoted_qr import pivoted_qr
from hil.arm.tool_frame import pose_parameter_names
from hil.calibration.distributions import f_sf
from hil.calibration.measurements import Measurements, measurements_sha256
from hil.calibration.prior import Prior, manufacturing_prior
from hil.errors import HilError, InputError

#: Smallest spread (rad) of a joint's values for it to count as having moved.
MIN_JOINT_SPREAD = 1e-3
#: Smallest RMS spread (m) of the measured points along a principal axis for it to count: arms whose
#: joints all move carry the SMR over tens of centimetres in every direction but at most one, so points
#: that vary along fewer than two axes by more than this were not measured on a moving arm.
MIN_POINT_SPREAD = 1e-3
#: Passes of the MAP refit, each with the prior's weights σ̂²/τ² from the previous pass's σ̂: the
#: noise estimate and the weights agree to a few per cent after two or three (they change little once
#: the prior stops moving the fit), and each pass is a warm-started LM of a few iterations.
PRIOR_PASSES = 3


class IdentificationError(HilError):
    """The fit failed to converge or produced a meaningless answer."""


@dataclass(frozen=True)
class RejectedPose:
    """A pose the outlier test removed from the fit."""

    index: int  # 0-based row of the input
    line: int  # line number in the input file
    residual: float  # residual norm (m) when it was rejected
    p_value: float  # leave-one-out F test p-value (before the Bonferroni correction)


@dataclass(frozen=True)
class Correlation:
    """A pair of identified parameters whose estimates are strongly correlated."""

    a: str
    b: str
    rho: float


@dataclass
class FitResult:
    """The calibrated geometry and everything a report needs about how well it is determined."""

    geometry: Geometry
    robot: Robot  # a catalog name, or the chain of an arm from its URDF
    indices: np.ndarray  # identified parameters (into EXTENDED_PARAMETER_NAMES: 51.. compliances,
    # 57.. joint errors and lost motion)
    values: np.ndarray  # their deviation from the nominal geometry (m, rad; SMR absolute)
    std: np.ndarray  # their standard deviations (local error coordinates at the solution)
    covariance: np.ndarray  # (n, n)
    rms: float  # fit RMS of the 3-D residual norms over the poses used (m)
    max_error: float  # largest residual norm among the poses used (m)
    sigma: float  # estimated per-axis measurement noise (m)
    initial_rms: float  # RMS after the tracker alignment, before the fit (m)
    iterations: int
    condition: float  # of the column-normalised Jacobian
    residuals: np.ndarray  # (m, 3) measured − model for every input pose (used or not)
    used: np.ndarray  # (m,) bool
    rejected: list[RejectedPose] = field(default_factory=list)
    correlated: list[Correlation] = field(default_factory=list)
    baseline: Geometry | None = None  # nominal arm with only the tracker pose and SMR fitted
    seconds: float = 0.0
    source: str = ""
    sha256: str = ""
    #: how the joint-error terms were chosen (`hil.calibration.joint_error_selection.TermChoice`)
    joint_error_choice: Any = None
    prior: Prior | None = None  # the MAP fit's prior on `indices` (None: plain least squares)
    prior_weights: np.ndarray | None = None  # (n,) σ²/τ² the fit used (m² per unit² of each parameter)
    #: a 6-D or several-reflector fit's additions (`hil.calibration.pose_identification.PoseFit`); its
    #: indices then name `hil.arm.tool_frame.pose_parameter_names`, tool.* and reflector<k>.* after the
    #: position fit's names (from 99 on a UR)
    pose_fit: Any = None

    @property
    def names(self) -> list[str]:
        table = pose_parameter_names(self.robot)
        return [table[i] for i in self.indices]

    @property
    def robot_name(self) -> str:
        """The robot's name as files and reports give it."""
        return robot_name(self.robot)

    @property
    def with_compliance(self) -> bool:
        """Whether the joints' compliance was identified with the geometry."""
        if not chain_of(self.robot).is_ur:
            return False
        return bool(np.any((self.indices >= N_PARAMETERS) & (self.indices < N_ALL_PARAMETERS)))

    @property
    def with_joint_errors(self) -> bool:
        """Whether joint-error or lost-motion terms were identified with the geometry."""
        if not chain_of(self.robot).is_ur:
            return False
        return bool(np.any((self.indices >= N_ALL_PARAMETERS)
                           & (self.indices < len(EXTENDED_PARAMETER_NAMES))))

    def prediction_covariance(self, q: np.ndarray) -> np.ndarray:
        """(N, 3, 3) covariance of the model's predicted SMR positions at configurations `q`."""
        J = Kinematics(self.geometry).jacobian(q, self.indices)
        return np.einsum("nij,jk,nlk->nil", J, self.covariance, J)


def minimum_poses(n_parameters: int) -> int:
    """Fewest poses that identify `n_parameters` and leave 3 residual degrees of freedom."""
    return -(-(n_parameters + 3) // 3)


def _parameters(robot: Robot, compliance: bool, template: Geometry,
                joint_errors: Sequence[int] = ()) -> np.ndarray:
    """The identified set: the geometry's, plus the identifiable compliances when asked, plus the
    joint-error terms `joint_errors` (indices into `EXTENDED_PARAMETER_NAMES`, 57..). An arm from its
    URDF has its geometry's only (InputError when more is asked)."""
    if compliance:
        refuse_non_ur(robot, "joint compliance")
    if len(joint_errors):
        refuse_non_ur(robot, "angle-dependent joint errors and lost motion")
    idx = (identifiable_parameters(robot) if not compliance
           else identifiable_with_compliance(robot, template.payload, template.gravity))
    # sorted(set()), not np.unique: numpy 2.4's unique imports numpy.ma (~50 ms of `hil identify`)
    terms = np.array(sorted({int(i) for i in np.asarray(joint_errors, dtype=int).ravel()}), dtype=int)
    if terms.size and (terms.min() < N_ALL_PARAMETERS or terms.max() >= len(EXTENDED_PARAMETER_NAMES)):
        raise ValueError(f"joint-error terms must index {N_ALL_PARAMETERS}.."
                         f"{len(EXTENDED_PARAMETER_NAMES) - 1}, got {terms.tolist()}")
    return np.r_[idx, terms].astype(int)


def check_design(meas: Measurements, robot: Robot, compliance: bool = False,
                 template: Geometry | None = None, joint_errors: Sequence[int] = ()) -> None:
    """Raise InputError if these poses cannot identify the model, naming what is wrong.

    `template` carries the payload and gravity the compliance columns need (its geometry is unused);
    `joint_errors` as in `identify`.
    """
    template = Geometry.nominal(robot) if template is None else template
    chain = chain_of(robot)
    if meas.q.shape[1] != chain.dof:
        raise InputError(f"{meas.source}: {meas.q.shape[1]} joint columns, but the {chain.name} has "
                         f"{chain.dof} joints (q1..q{chain.dof})")
    idx = _parameters(robot, compliance, template, joint_errors)
    n, m, src = len(idx), len(meas), meas.source
    need = minimum_poses(n)
    if m < need:
        raise InputError(f"{src}: {m} poses, but identifying {n} parameters from 3 coordinates per "
                         f"pose needs at least {need}")
    spread = np.ptp(meas.q, axis=0)
    if np.max(np.linalg.norm(meas.q - meas.q[0], axis=1)) < MIN_JOINT_SPREAD:
        raise InputError(f"{src}: all {m} poses are the same joint configuration")
    still = [f"q{j + 1}" for j in range(chain.dof) if spread[j] < MIN_JOINT_SPREAD]
    if still:
        raise InputError(f"{src}: column(s) {', '.join(still)} never change (spread below "
                         f"{MIN_JOINT_SPREAD} rad): every joint must move for its parameters to be "
                         "identifiable")
    generic = generic_geometry(robot)
    generic.payload, generic.gravity = template.payload, template.gravity
    J = Kinematics(generic).jacobian(meas.q, idx, meas.directions).reshape(-1, n)
    if numerical_rank(J) < n:
        norms = np.linalg.norm(J, axis=0)
        _, d, piv = pivoted_qr(J / norms)
        names = parameter_names(robot)
        lost = [names[idx[piv[k]]] for k in range(n) if d[k] <= 1e-7 * d[0]]
        raise InputError(f"{src}: degenerate pose set: the poses cannot identify {', '.join(lost)} "
                         "(use more distinct poses that move every joint)")
    extent = np.linalg.svd(meas.p - meas.p.mean(axis=0), compute_uv=False) / np.sqrt(m)
    rank = int(np.sum(extent > MIN_POINT_SPREAD))
    if rank < 2:
        shape = "are all the same point" if rank == 0 else "all lie on one line"
        raise InputError(f"{src}: the measured points x,y,z {shape} (rank {rank} of 3, spread above "
                         f"{MIN_POINT_SPREAD * 1e3:g} mm) although the joints move: the data cannot "
                         "identify the arm; check the x,y,z columns")


def kabsch_rotation(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rotation R minimising Σ‖aᵢ − R·bᵢ‖² over centred point sets `a`, `b` (n × 3): Kabsch's
    (1976) closed form from the SVD of the 3 × 3 cross-covariance, a reflection turned into a rotation.

    What ``scipy.spatial.transform.Rotation.align_vectors`` computes, without its import (0.08 s of
    ``hil identify``'s start-up, for one 3 × 3 SVD).
    """
    U, _, Vt = np.linalg.svd(b.T @ a)
    flip = np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0
    return Vt.T @ np.diag([1.0, 1.0, flip]) @ U.T


def align_tracker(geometry: Geometry, meas: Measurements) -> Geometry:
    """`geometry` with its tracker pose from a closed-form rigid fit of modelled to measured points."""
    base = Kinematics(geometry).points(meas.q, frame="base")
    ca, cb = meas.p.mean(axis=0), base.mean(axis=0)
    R = kabsch_rotation(meas.p - ca, base - cb)  # measured ≈ R·base + t
    t = ca - R @ cb
    out = geometry.copy()
    out.tracker.rotation = R.T
    out.tracker.translation = -R.T @ t
    return out


@dataclass
class _State:
    geometry: Geometry
    p: np.ndarray
    J: np.ndarray  # (m, 3, 51), (m, 3, 57) with the compliance columns, (m, 3, 99) with joint errors
    compliance: bool = False
    directions: np.ndarray | None = None  # (m, 6) each joint's last motion, for lost motion
    joint_errors: bool = False

    @classmethod
    def at(cls, geometry: Geometry, q: np.ndarray, compliance: bool = False,
           directions: np.ndarray | None = None, joint_errors: bool = False) -> _State:
        p, J = Kinematics(geometry).point_and_jacobian(q, compliance, directions, joint_errors)
        return cls(geometry, p, J, compliance, directions, joint_errors)

    def subset(self, rows: np.ndarray) -> _State:
        d = None if self.directions is None else self.directions[rows]
        return _State(self.geometry, self.p[rows], self.J[rows], self.compliance, d, self.joint_errors)


@dataclass(frozen=True)
class _PriorRows:
    """The prior's residual rows √w·(θ − θ₀), θ the deviation of the fitted geometry from nominal."""

    reference: Geometry  # the nominal arm the deviation is taken from
    prior: Prior
    weights: np.ndarray  # (n,) σ²/τ²

    def offset(self, geometry: Geometry, compliance: bool) -> np.ndarray:
        extended = bool(np.any(self.prior.indices >= N_ALL_PARAMETERS))
        return (deviation_from(self.reference, geometry, compliance, extended)[self.prior.indices]
                - self.prior.mean)

    def cost(self, geometry: Geometry, compliance: bool) -> float:
        d = self.offset(geometry, compliance)
        return float(np.sum(self.weights * d * d))


def _levenberg_marquardt(state: _State, q: np.ndarray, p_meas: np.ndarray, idx: np.ndarray,
                         max_iter: int, prior: _PriorRows | None = None) -> tuple[_State, int, bool]:
    """Minimise Σ‖p_meas − p(q)‖² (+ the prior's Σ w·(θ − θ₀)²) over the parameters `idx`; returns
    (state, iterations, converged).

    The prior's rows have the identity as their Jacobian: the step is local (T·exp(δ)) and the prior
    is on log(nominal⁻¹·T), equal to first order at the millimetre/milliradian errors of an arm.
    """
    r = (p_meas - state.p).ravel()
    cost = float(r @ r) + (prior.cost(state.geometry, state.compliance) if prior else 0.0)
    lam = 1e-3
    for it in range(1, max_iter + 1):
        J = state.J[:, :, idx].reshape(-1, len(idx))
        A = J.T @ J
        g = J.T @ r
        if prior is not None:
            A = A + np.diag(prior.weights)
            g = g - prior.weights * prior.offset(state.geometry, state.compliance)
        D = np.maximum(np.diag(A), 1e-30)
        improved = False
        while lam < 1e12:
            # positive definite (D > 0, λ > 0); degenerate data: the rank check after the fit says so
            step = np.linalg.solve(A + lam * np.diag(D), g)
            full = np.zeros(state.J.shape[2])
            full[idx] = step
            cand = _State.at(apply_update(state.geometry, full), q, state.compliance, state.directions,
                             state.joint_errors)
            r_c = (p_meas - cand.p).ravel()
            cost_c = float(r_c @ r_c) + (prior.cost(cand.geometry, cand.compliance) if prior else 0.0)
            if cost_c < cost:
                improved = True
                break
            lam *= 4.0
        if not improved:
            return state, it, True  # no step lowers the cost: at the minimum to working precision
        drop = cost - cost_c
        state, r, cost = cand, r_c, cost_c
        lam = max(lam / 3.0, 1e-12)
        if drop <= 1e-12 * cost + 1e-30 or np.max(np.abs(step) * np.sqrt(D)) < 1e-12:
            return state, it, True
    return state, max_iter, False


def _statistics(J: np.ndarray, r: np.ndarray,
                weights: np.ndarray | None = None) -> tuple[np.ndarray, float, float]:
    """(JᵀJ + W)⁻¹, σ̂² and the condition number, via column normalisation for numerical stability.

    With a prior's weights W the residual degrees of freedom are rows − trace(J (JᵀJ + W)⁻¹ Jᵀ) (the
    effective number of parameters the data, not the prior, determine); without one, rows − n.
    The condition number is the data's (of the column-normalised J), prior or not.
    """
    norms = np.linalg.norm(J, axis=0)
    Js = J / norms
    s = np.linalg.svd(Js, compute_uv=False)
    A = Js.T @ Js
    if weights is None:
        inv = np.linalg.pinv(A) / np.outer(norms, norms)
        dof = J.shape[0] - J.shape[1]
    else:
        inv = np.linalg.pinv(A + np.diag(weights / norms**2)) / np.outer(norms, norms)
        dof = J.shape[0] - float(np.sum((J.T @ J) * inv))
    sigma2 = float(r @ r) / dof if dof > 0 else float("nan")
    return inv, sigma2, float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


def chi2_3_sf(x: float) -> float:
    """P(χ² > x) for 3 degrees of freedom, in closed form: erfc(√(x/2)) + √(2x/π)·e^(−x/2)
    (Abramowitz & Stegun 26.4.4 with ν = 3)."""
    x = max(x, 0.0)
    return math.erfc(math.sqrt(x / 2.0)) + math.sqrt(2.0 * x / math.pi) * math.exp(-x / 2.0)


def f_3_sf_lower_bound(f: float) -> float:
    """A lower bound of P(F > f) for F(3, ν₂), whatever ν₂ ≥ 1: P(χ²₃ > max(3f, 3)).

    Why: F = X/Y with X = χ²₃/3 and Y = χ²_ν₂/ν₂ independent, E[Y] = 1, so P(F > f) = E[g(Y)] with
    g(y) = P(χ²₃ > 3fy). For 3f ≥ 3, g is convex on y ≥ 1/(3f) (χ²₃'s density falls beyond its mode
    at 1) and concave below; its tangent at y = 1 stays under it on both pieces (at y = 0 it reaches
    g(1) + 3f·p(3f) ≤ 0.86 < 1 = g(0), p χ²₃'s density), so by Jensen E[g(Y)] ≥ g(1) = P(χ²₃ > 3f).
    For 3f < 3 the survival function only grows as f falls. The F tail is heavier than χ²'s: the
    bound tightens as ν₂ grows (tests/hil/calibration/test_identification_outlier_test.py checks it
    against scipy's F distribution).
    """
    return chi2_3_sf(max(3.0 * f, 3.0))


def _outlier(Jp: np.ndarray, res: np.ndarray, inv: np.ndarray, level: float) -> tuple[int, float] | None:
    """(index among the used poses, F-test p-value) of the most significant outlier if its p-value is
    below `level`, else None.

    The p-values are the F distribution's tail (`hil.calibration.distributions.f_sf`, scipy's to 1e-10
    without its import), computed only when the largest F statistic could be significant
    (`f_3_sf_lower_bound`).
    """
    m, n = Jp.shape[0], Jp.shape[2]
    dof = 3 * m - n
    if dof - 3 < 1:
        return None
    H = np.einsum("nij,jk,nlk->nil", Jp, inv, Jp)  # leverage blocks
    Q = np.linalg.pinv(np.eye(3) - H)
    qi = np.einsum("ni,nij,nj->n", res, Q, res)
    ssr = float(np.sum(res * res))
    s2_loo = np.maximum(ssr - qi, 1e-300) / (dof - 3)
    F = qi / (3.0 * s2_loo)
    if f_3_sf_lower_bound(float(np.max(F))) >= level:
        return None
    pvals = np.array([f_sf(float(f), 3.0, float(dof - 3)) for f in F])
    k = int(np.argmin(pvals))
    return (k, float(pvals[k])) if pvals[k] < level else None


def _registration(robot: Robot) -> np.ndarray:
    """Indices of the tracker pose and the SMR offset in `robot`'s parameter vector."""
    return parameter_layout(chain_of(robot).dof).registration


def register(meas: Measurements, robot: Robot, smr_guess: np.ndarray | None = None,
             max_iter: int = 50, *, arm: Geometry | None = None) -> Geometry:
    """The nominal arm with only the tracker pose and the SMR offset fitted to `meas`.

    This is "before calibration": what the arm's own kinematics achieve once the tracker is
    registered. Works from 3 non-collinear poses (the SMR offset is then poorly determined).
    `arm` replaces the nominal joints and flange by another model's (the controller's own), so that
    model is judged the same way.
    """
    nominal = Geometry.nominal(robot, smr=(0.0, 0.0, 0.0) if smr_guess is None else smr_guess)
    if arm is not None:
        nominal = Geometry(nominal.robot, list(arm.joints), arm.flange, nominal.smr, nominal.tracker,
                           chain=nominal.chain)
    state = _State.at(align_tracker(nominal, meas), meas.q)
    state, _, _ = _levenberg_marquardt(state, meas.q, meas.p, _registration(robot), max_iter)
    return state.geometry


def identify(meas: Measurements, robot: Robot, smr_guess: np.ndarray | None = None, *,
             reject_outliers: bool = True, alpha: float = 0.01, max_iter: int = 100,
             correlation_threshold: float = 0.95, compliance: bool = False,
             payload: Payload | None = None, gravity: np.ndarray | None = None,
             joint_errors: Sequence[int] = (), prior: bool = True) -> FitResult:
    """Identify the calibration geometry of `robot` from `meas` (see the module docstring).

    With `compliance` the joints' compliance is identified too, for the arm carrying `payload` under
    `gravity` (base frame; default floor mounting): the model then carries both and predicts the sag.
    `joint_errors` names joint-error and lost-motion terms to identify beside them (indices into
    `EXTENDED_PARAMETER_NAMES`; which ones the data support is `hil.calibration.joint_error_selection`'s
    question); the model then carries its ``joint_errors`` and ``lost_motion`` blocks.
    `prior` (default) makes it the MAP fit toward the nominal geometry (`hil.calibration.prior`);
    False gives the plain least-squares fit. `robot` is a catalog name or, for any other serial arm,
    its chain (`hil.arm.urdf_chain.chain_from_urdf`): then the geometry alone is identified.
    """
    t0 = time.perf_counter()
    nominal = Geometry.nominal(robot, smr=(0.0, 0.0, 0.0) if smr_guess is None else smr_guess)
    nominal.payload = payload
    if gravity is not None:
        nominal.gravity = np.asarray(gravity, dtype=float)
    check_design(meas, robot, compliance, nominal, joint_errors)
    idx = _parameters(robot, compliance, nominal, joint_errors)
    extended = bool(np.any(idx >= N_ALL_PARAMETERS))
    n, m = len(idx), len(meas)
    if compliance:
        nominal.compliance = np.zeros(6)
    start = align_tracker(nominal, meas)
    used = np.ones(m, dtype=bool)
    state = _State.at(start, meas.q, compliance, meas.directions, extended)
    initial_rms = float(np.sqrt(np.mean(np.sum((meas.p - state.p) ** 2, axis=1))))

    # Tracker pose and SMR offset first: a far-off SMR guess otherwise drags the joints around.
    state, iterations, _ = _levenberg_marquardt(state, meas.q, meas.p, _registration(robot), max_iter)
    baseline = state.geometry
    rejected: list[RejectedPose] = []
    max_reject = min(m // 5, m - minimum_poses(n))
    while True:
        q_u, p_u = meas.q[used], meas.p[used]
        sub, its, converged = _levenberg_marquardt(state.subset(used), q_u, p_u, idx, max_iter)
        iterations += its
        state = _State.at(sub.geometry, meas.q, compliance, meas.directions, extended)
        res = meas.p - state.p
        Jp = state.J[used][:, :, idx]
        inv, sigma2, cond = _statistics(Jp.reshape(-1, n), res[used].ravel())
        if not reject_outliers or len(rejected) >= max_reject:
            break
        worst = _outlier(Jp, res[used], inv, alpha / used.sum())
        if worst is None:
            break
        k, pval = worst
        row = int(np.flatnonzero(used)[k])
        used[row] = False
        rejected.append(RejectedPose(row, int(meas.lines[row]), float(np.linalg.norm(res[row])), pval))
    rank = numerical_rank(Jp.reshape(-1, n))
    if rank < n:  # the data fitted only by a collapsed arm: an answer, but not an identification
        raise InputError(f"{meas.source}: the data cannot identify the {n} parameters: at the fitted "
                         f"model the Jacobian has numerical rank {rank} of {n} (condition number "
                         f"{cond:.3g}); the measured points do not follow the joint motion")
    tolerance, weights = None, None
    if prior:
        tolerance = manufacturing_prior(robot, idx)
        rows = _PriorRows(Geometry.nominal(robot), tolerance, tolerance.weights(np.sqrt(sigma2)))
        q_u, p_u = meas.q[used], meas.p[used]
        for _ in range(PRIOR_PASSES):  # σ̂ and the weights σ̂²/τ² to agreement
            sub, its, converged = _levenberg_marquardt(state.subset(used), q_u, p_u, idx, max_iter, rows)
            iterations += its
            state = _State.at(sub.geometry, meas.q, compliance, meas.directions, extended)
            res = meas.p - state.p
            Jp = state.J[used][:, :, idx]
            inv, new_sigma2, cond = _statistics(Jp.reshape(-1, n), res[used].ravel(), rows.weights)
            settled = abs(new_sigma2 - sigma2) <= 0.02 * sigma2
            sigma2 = new_sigma2
            if settled:
                break
            rows = _PriorRows(rows.reference, tolerance, tolerance.weights(np.sqrt(sigma2)))
        weights = rows.weights
    if not converged:
        raise IdentificationError(f"{meas.source}: the fit did not converge in {max_iter} iterations")
    cov = sigma2 * inv
    std = np.sqrt(np.maximum(np.diag(cov), 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(std, std)
    table = parameter_names(robot)
    names = [table[i] for i in idx]
    correlated = [Correlation(names[a], names[b], float(corr[a, b]))
                  for a in range(n) for b in range(a + 1, n)
                  if abs(corr[a, b]) >= correlation_threshold]
    correlated.sort(key=lambda c: -abs(c.rho))
    reference = Geometry.nominal(robot)
    values = deviation_from(reference, state.geometry, compliance, extended)[idx]
    norms = np.linalg.norm(res[used], axis=1)
    return FitResult(
        geometry=state.geometry, robot=robot, indices=idx, values=values, std=std, covariance=cov,
        rms=float(np.sqrt(np.mean(norms**2))), max_error=float(norms.max()),
        sigma=float(np.sqrt(sigma2)), initial_rms=initial_rms, iterations=iterations,
        condition=cond, residuals=res, used=used, rejected=rejected, correlated=correlated,
        baseline=baseline, seconds=time.perf_counter() - t0, source=meas.source,
        sha256=meas.sha256 or measurements_sha256(meas.q, meas.p),  # a model always names its data
        prior=tolerance, prior_weights=weights)


@dataclass(frozen=True)
class ErrorStats:
    """Distances between predicted and measured (or true) points."""

    count: int
    mean: float
    rms: float
    max: float
    errors: np.ndarray  # (m,) 3-D distances, metres

    @classmethod
    def of(cls, errors: np.ndarray) -> ErrorStats:
        e = np.linalg.norm(np.asarray(errors, dtype=float).reshape(-1, 3), axis=1)
        return cls(len(e), float(e.mean()), float(np.sqrt(np.mean(e**2))), float(e.max()), e)

    def as_dict(self) -> dict[str, float | int]:
        return {"count": self.count, "mean": self.mean, "rms": self.rms, "max": self.max}


def validate(geometry: Geometry, meas: Measurements) -> ErrorStats:
    """Errors of `geometry`'s predictions against measured points it was not fitted to."""
    return ErrorStats.of(meas.p - Kinematics(geometry).points(meas.q, directions=meas.directions))
