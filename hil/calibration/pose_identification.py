"""Identification from 6-D measurements (a camera, a 6-DoF probe) and from several reflectors per pose.

A file with orientations measures the tool *frame*; one with several reflectors several points of one
tool. This fit uses all of it (`hil.arm.tool_frame` for the model and its Jacobian): every reflector's
position is a residual (metres), and the measured frame's orientation is one too (the small rotation
vector log(R_measured·R_modelᵀ), radians). The two kinds are divided by their own noise —
`position_noise` and `orientation_noise` as stated (``--position-noise``, ``--orientation-noise``) — so
each residual is in units of its σ and they add in one sum. Only their ratio weighs one kind against the
other: the overall scale ŝ (the whitened residuals' RMS, ≈ 1 when the stated noises are right) is
estimated from the data, as the position fit estimates σ̂, and reported.

Steps, as the position fit's (`hil.calibration.identification`): check the data; register the nominal
arm (Kabsch, then the tracker pose and SMR offset by Levenberg–Marquardt, `register`); place the tool in
closed form — its rotation R_tool = proj_SO(3) Σ R_bf(qᵢ)ᵀ·R_bt·Rᵢ, each further reflector at the mean of
its measured points carried into the flange frame — and refine the whole registration (tracker, SMR,
tool rotation, reflectors; the *nominal* model of the cross-validation); fit the identifiable set
(`identifiable_tool_parameters`: 30 for a UR with orientations, 27 + 3 per further reflector without);
reject outliers one pose at a time (the leave-one-out F test on the pose's block of rows, Bonferroni at
α = 1 %); then, unless told not to, the MAP refit with the manufacturing tolerances
(`hil.calibration.prior`) on the joints and flange (none on the tracker and the tool: where the user put
them is not a tolerance), weights ŝ²/τ² iterated to agreement.

The 6-D fit models the geometry only: compliance and joint-error terms are not identified with it (the
command line says so rather than dropping them silently).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from hil.arm import tool_frame as tf
from hil.arm.chain import Robot, chain_of
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics, numerical_rank, parameter_layout
from hil.calibration.distributions import f_sf
from hil.calibration.identification import (
    PRIOR_PASSES,
    Correlation,
    FitResult,
    IdentificationError,
    RejectedPose,
    _statistics,
    check_design,
    register,
)
from hil.calibration.measurements import Measurements, measurements_sha256
from hil.calibration.prior import Prior, manufacturing_prior
from hil.errors import InputError
from hil.files.quantities import quantity

#: Default σ (m per axis) of a position a camera on a chessboard measures. An assumption, stated as
#: one: we found no published figure for this set-up. The shared UR10e camera file's README (a RealSense
#: D435 on the flange, a 10 × 7 board of 2.7 cm squares at about 1 m) says "a few millimetres", and the
#: position fit of that file finds σ̂ ≈ 1.9 mm. Only the ratio to `ORIENTATION_NOISE` weighs the two
#: kinds of residual; the fit estimates the overall scale itself.
POSITION_NOISE = 2e-3
#: Default σ (rad per axis) of the orientation a camera on a chessboard measures. An assumption from the
#: geometry of the measurement: a planar target's pose from one image (PnP) confounds a tilt δθ of the
#: camera with a sideways shift Z·δθ of the board at distance Z, which moves the image alike, so the
#: two errors come together in the ratio 1/Z: at Z ≈ 1 m, 1 mrad per mm of position noise. For a
#: tracker's 6-DoF probe give both noises (``--position-noise``, ``--orientation-noise``).
ORIENTATION_NOISE = 2e-3
#: The outlier test's level (before Bonferroni), as the position fit's.
ALPHA = 0.01


@dataclass
class PoseFit:
    """What a 6-D or several-reflector fit adds to a `FitResult` (its ``pose_fit``)."""

    orientation: bool  # orientations were fitted
    reflectors: int
    position_noise: float  # m, as stated
    orientation_noise: float  # rad, as stated
    scale: float  # ŝ: RMS of the whitened residuals over the degrees of freedom (1: noises as stated)
    local: np.ndarray  # identified columns of the local layout (`hil.arm.tool_frame`)
    reflector_residuals: np.ndarray  # (m, R, 3) m, measured − model
    orientation_residuals: np.ndarray | None  # (m, 3) rad, log(R_measured·R_modelᵀ)

    @property
    def rows(self) -> int:
        """Residual rows per pose."""
        return 3 * self.reflectors + (3 if self.orientation else 0)

    def whiten(self) -> np.ndarray:
        """(rows,) the divisor of each row of a pose: its kind's stated noise."""
        w = np.full(self.rows, self.position_noise)
        if self.orientation:
            w[-3:] = self.orientation_noise
        return w

    def orientation_rms(self, used: np.ndarray) -> float | None:
        """RMS angle (rad) of the orientation residuals over the used poses (None: no orientations)."""
        if self.orientation_residuals is None:
            return None
        return float(np.sqrt(np.mean(np.sum(self.orientation_residuals[used] ** 2, axis=1))))

    def as_dict(self, used: np.ndarray) -> dict[str, Any]:
        """The model's ``fit.pose_fit`` block (docs/design.md)."""
        pos = np.linalg.norm(self.reflector_residuals[used], axis=2)
        return {"orientation": self.orientation, "reflectors": self.reflectors,
                "position_noise": self.position_noise, "orientation_noise": self.orientation_noise,
                "scale": self.scale, "position_rms": float(np.sqrt(np.mean(pos**2))),
                "orientation_rms": self.orientation_rms(used),
                "position_sigma": self.scale * self.position_noise,
                "orientation_sigma": self.scale * self.orientation_noise if self.orientation else None}


def uses_tool(meas: Measurements) -> bool:
    """Whether `meas` has more than one position per pose: orientations or several reflectors."""
    return meas.rotation is not None or (meas.reflectors is not None and meas.reflectors.shape[1] > 1)


def _measured(meas: Measurements) -> np.ndarray:
    """(m, R, 3) every reflector's measured position."""
    return meas.p[:, None, :] if meas.reflectors is None else meas.reflectors


@dataclass
class _Problem:
    """The measurements, whitened, and how to evaluate a geometry against them."""

    q: np.ndarray
    points: np.ndarray  # (m, R, 3)
    rotation: np.ndarray | None  # (m, 3, 3)
    scale: np.ndarray  # (rows,) each row's stated noise

    def evaluate(self, g: Geometry) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
        """Whitened residuals (m, rows), whitened Jacobian (m, rows, width), position residuals (m, R, 3)
        and orientation residuals (m, 3) or None."""
        p, R, J = tf.frame_and_jacobian(g, self.q, self.rotation is not None)
        dp = self.points - p
        parts = [dp.reshape(len(dp), -1)]
        do = None
        if self.rotation is not None:
            do = tf.rotation_residuals(self.rotation, R)
            parts.append(do)
        r = np.concatenate(parts, axis=1) / self.scale
        return r, J / self.scale[None, :, None], dp, do

    def subset(self, rows: np.ndarray) -> _Problem:
        return _Problem(self.q[rows], self.points[rows],
                        None if self.rotation is None else self.rotation[rows], self.scale)


@dataclass(frozen=True)
class _Prior:
    reference: Geometry
    prior: Prior
    local: np.ndarray
    weights: np.ndarray

    def offset(self, g: Geometry) -> np.ndarray:
        return tf.tool_deviation(self.reference, g)[self.local] - self.prior.mean


def _lm(g: Geometry, problem: _Problem, local: np.ndarray, max_iter: int,
        prior: _Prior | None = None) -> tuple[Geometry, int, bool]:
    """Levenberg–Marquardt over the local columns `local`, steps applied by `apply_tool_update` (the
    position fit's loop, `identification._levenberg_marquardt`, on whitened rows)."""
    r, J, _, _ = problem.evaluate(g)

    def cost_of(res: np.ndarray, geo: Geometry) -> float:
        extra = 0.0 if prior is None else float(np.sum(prior.weights * prior.offset(geo) ** 2))
        return float(np.sum(res * res)) + extra

    cost = cost_of(r, g)
    lam = 1e-3
    width = J.shape[2]
    for it in range(1, max_iter + 1):
        Jl = J[:, :, local].reshape(-1, len(local))
        A = Jl.T @ Jl
        grad = Jl.T @ r.ravel()
        if prior is not None:
            A = A + np.diag(prior.weights)
            grad = grad - prior.weights * prior.offset(g)
        D = np.maximum(np.diag(A), 1e-30)
        improved = False
        while lam < 1e12:
            step = np.linalg.solve(A + lam * np.diag(D), grad)
            full = np.zeros(width)
            full[local] = step
            cand = tf.apply_tool_update(g, full)
            r_c, J_c, _, _ = problem.evaluate(cand)
            cost_c = cost_of(r_c, cand)
            if cost_c < cost:
                improved = True
                break
            lam *= 4.0
        if not improved:
            return g, it, True
        drop = cost - cost_c
        g, r, J, cost = cand, r_c, J_c, cost_c
        lam = max(lam / 3.0, 1e-12)
        if drop <= 1e-12 * cost + 1e-30 or np.max(np.abs(step) * np.sqrt(D)) < 1e-12:
            return g, it, True
    return g, max_iter, False


def _project_rotation(M: np.ndarray) -> np.ndarray:
    """The rotation nearest `M` (Frobenius): U·diag(1, 1, det)·Vᵀ of its SVD."""
    U, _, Vt = np.linalg.svd(M)
    return U @ np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt)) or 1.0]) @ Vt


def place_tool(g: Geometry, problem: _Problem) -> Geometry:
    """`g` with its tool rotation and further reflectors placed in closed form (module docstring)."""
    out = g.copy()
    F = Kinematics(g).flange_poses(problem.q)
    T = g.tracker
    if problem.rotation is not None:
        out.tool_rotation = _project_rotation(
            np.einsum("nji,jk,nkl->il", F[:, :3, :3], T.rotation, problem.rotation))
    if problem.points.shape[1] > 1:
        base = problem.points @ T.rotation.T + T.translation  # (m, R, 3) in the base frame
        local = np.einsum("nji,nkj->nki", F[:, :3, :3], base - F[:, None, :3, 3])
        out.reflectors = local.mean(axis=0)
        out.reflectors[0] = out.smr
    return out


def _outlier(Ju: np.ndarray, res: np.ndarray, inv: np.ndarray, level: float) -> tuple[int, float] | None:
    """(index among used poses, p-value) of the most significant outlier below `level`, else None: the
    position fit's leave-one-out F test (`identification._outlier`) on blocks of b rows per pose."""
    m, b, n = Ju.shape
    dof = b * m - n
    if dof - b < 1:
        return None
    H = np.einsum("nij,jk,nlk->nil", Ju, inv, Ju)
    Q = np.linalg.pinv(np.eye(b) - H)
    qi = np.einsum("ni,nij,nj->n", res, Q, res)
    s2 = np.maximum(float(np.sum(res * res)) - qi, 1e-300) / (dof - b)
    F = qi / (b * s2)
    k = int(np.argmax(F))
    p = f_sf(float(F[k]), float(b), float(dof - b))
    return (k, p) if p < level else None


def identify_pose(meas: Measurements, robot: Robot, smr_guess: np.ndarray | None = None, *,
                  position_noise: float = POSITION_NOISE, orientation_noise: float = ORIENTATION_NOISE,
                  reject_outliers: bool = True, prior: bool = True, max_iter: int = 100,
                  arm: Geometry | None = None, registration_only: bool = False) -> FitResult:
    """The 6-D / several-reflector fit of `meas` (module docstring), as a `FitResult` whose
    ``pose_fit`` holds what it adds. `arm` replaces the nominal joints and flange (the controller's
    model, registered as the nominal is); `registration_only` stops after the registration (a
    nominal or controller model placed on the data). `robot` is a catalog name or any serial arm's chain
    (`hil.arm.urdf_chain.chain_from_urdf`): its N joints give the local layout (`hil.arm.tool_frame`)."""
    t0 = time.perf_counter()
    for name, value, row in (("--position-noise", position_noise, "position noise"),
                             ("--orientation-noise", orientation_noise, "orientation noise")):
        quantity(row).check(float(value), name)
    check_design(meas, robot)
    orientation = meas.rotation is not None
    points = _measured(meas)
    count = points.shape[1]
    if count > tf.MAX_REFLECTORS:
        raise InputError(f"{meas.source}: {count} reflectors per pose, hil fits at most {tf.MAX_REFLECTORS}")
    scale = np.r_[np.full(3 * count, position_noise), np.full(3 if orientation else 0, orientation_noise)]
    problem = _Problem(meas.q, points, meas.rotation, scale)
    m = len(meas)
    start = register(meas, robot, smr_guess, max_iter, arm=arm)
    start = tf.with_tool(start, count, orientation)
    start = place_tool(start, problem)
    dof = chain_of(robot).dof
    reg_cols = tf.registration_columns(count, orientation, dof)
    baseline, iterations, _ = _lm(start, problem, reg_cols, max_iter)
    local = reg_cols if registration_only else tf.identifiable_tool_parameters(robot, count, orientation)
    n = len(local)
    b = problem.scale.size
    need = -(-(n + b) // b)
    if m < need:
        raise InputError(f"{meas.source}: {m} poses, but identifying {n} parameters from {b} values per "
                         f"pose needs at least {need}")
    _, _, initial, _ = problem.evaluate(start)
    g = baseline
    used = np.ones(m, dtype=bool)
    rejected: list[RejectedPose] = []
    max_reject = 0 if registration_only else min(m // 5, m - need)
    converged = True
    while True:
        g, its, converged = _lm(g, problem.subset(used), local, max_iter)
        iterations += its
        r, J, dp, do = problem.evaluate(g)
        Ju = J[used][:, :, local]
        inv, s2, cond = _statistics(Ju.reshape(-1, n), r[used].ravel())
        if not reject_outliers or len(rejected) >= max_reject:
            break
        worst = _outlier(Ju, r[used], inv, ALPHA / used.sum())
        if worst is None:
            break
        k, pval = worst
        row = int(np.flatnonzero(used)[k])
        used[row] = False
        rejected.append(RejectedPose(row, int(meas.lines[row]), float(np.linalg.norm(dp[row, 0])), pval))
    if numerical_rank(Ju.reshape(-1, n)) < n:
        raise InputError(f"{meas.source}: the data cannot identify the {n} parameters of the 6-D fit "
                         f"(condition number {cond:.3g}); the measurements do not follow the joint motion")
    tolerance, weights = None, None
    names = tf.to_names(local, robot)
    if prior and not registration_only:
        geometric = local < parameter_layout(dof).size
        base = manufacturing_prior(robot, local[geometric])
        mean, std = np.zeros(n), np.full(n, np.inf)
        mean[geometric], std[geometric] = base.mean, base.std
        tolerance = Prior(names, mean, std)
        rows = _Prior(Geometry.nominal(robot), tolerance, local, tolerance.weights(np.sqrt(s2)))
        for _ in range(PRIOR_PASSES):
            g, its, converged = _lm(g, problem.subset(used), local, max_iter, rows)
            iterations += its
            r, J, dp, do = problem.evaluate(g)
            Ju = J[used][:, :, local]
            inv, new_s2, cond = _statistics(Ju.reshape(-1, n), r[used].ravel(), rows.weights)
            settled = abs(new_s2 - s2) <= 0.02 * s2
            s2 = new_s2
            if settled:
                break
            rows = _Prior(rows.reference, tolerance, local, tolerance.weights(np.sqrt(s2)))
        weights = rows.weights
    if not converged:
        raise IdentificationError(f"{meas.source}: the fit did not converge in {max_iter} iterations")
    cov = s2 * inv  # rows are whitened, the parameters physical: the posterior covariance
    std = np.sqrt(np.maximum(np.diag(cov), 0.0))
    # deviation from the nominal arm carrying a tool at its SMR guess: the tool rotation's value is
    # log(R_tool) and the reflectors' offsets are absolute, as the SMR's
    values = tf.tool_deviation(tf.with_tool(Geometry.nominal(robot), count, orientation), g)[local]
    norms = np.linalg.norm(dp[used], axis=2)
    info = PoseFit(orientation, count, position_noise, orientation_noise, float(np.sqrt(s2)), local, dp, do)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(std, std)
    table = tf.pose_parameter_names(robot)
    labels = [table[i] for i in names]
    correlated = sorted((Correlation(labels[a], labels[c], float(corr[a, c]))
                         for a in range(n) for c in range(a + 1, n) if abs(corr[a, c]) >= 0.95),
                        key=lambda c: -abs(c.rho))
    return FitResult(
        geometry=g, robot=robot, indices=names, values=values, std=std, covariance=cov,
        rms=float(np.sqrt(np.mean(norms**2))), max_error=float(norms.max()),
        sigma=float(np.sqrt(s2)) * position_noise,
        initial_rms=float(np.sqrt(np.mean(np.sum(initial**2, axis=2)))),
        iterations=iterations, condition=cond, residuals=dp[:, 0].copy(), used=used, rejected=rejected,
        correlated=correlated, baseline=baseline, seconds=time.perf_counter() - t0, source=meas.source,
        sha256=meas.sha256 or measurements_sha256(meas.q, meas.p), prior=tolerance,
        prior_weights=weights, pose_fit=info)


def whitened(meas: Measurements, geometry: Geometry, info: PoseFit) -> tuple[np.ndarray, np.ndarray]:
    """Whitened residuals (m, rows) and Jacobian (m, rows, local width) of `geometry` against `meas`
    as the fit `info` weighs them (the cross-validation's input)."""
    problem = _Problem(meas.q, _measured(meas), meas.rotation if info.orientation else None, info.whiten())
    r, J, _, _ = problem.evaluate(geometry)
    return r, J
