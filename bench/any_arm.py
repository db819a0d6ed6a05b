"""Any serial arm from its URDF: identification accuracy against the Cramér–Rao prediction, and speed.

Arms: the Franka Panda (7 joints), the Kinova Jaco j2s6s200 and the Unitree Z1 (6 each) from the
``example-robot-data`` package's URDFs, and the UR5e twice — through a URDF built from its DH table
(`hil.calibration.exports.to_urdf`) and through the catalog, which must give identical results.

Each trial is one synthetic station (`hil.calibration.synthetic.random_truth(..., rigid=True)`): every
joint origin and the flange carry a random placement error of σ 0.5 mm per translation axis and 1 mrad
per rotation axis — hil's synthetic default, half the manufacturing tolerance its prior assumes
(`hil.calibration.prior` cites it; an assumption for the non-UR arms, whose makers publish none) — an
unknown SMR offset and an unknown tracker pose 2–4 m away. The points err as the AT960 does
(`hil.calibration.tracker_noise`: 7.5 µm along the beam, 3 µrad per angle across it); the joints read
exactly (the bound below counts the tracker's noise only). `--poses` random poses within the URDF's
limits are identified (`hil.calibration.identification.identify`, the MAP fit as `hil identify` runs
it); the held-out error is the RMS distance between the calibrated model and the truth over 500 fresh
poses. The Cramér–Rao prediction for the same poses is mean trace(J_v (Σ J_iᵀ W_i J_i)⁻¹ J_vᵀ), with
W_i the inverse of each point's noise covariance as `perturb_points` draws it (σ_d² along the beam,
(d·σ_a)² along the zenith angle's direction, (d·sin(zenith)·σ_a)² along the horizontal angle's). Both
are pooled over trials as root-mean-square. The UR5e's two rows calibrate the same stations: the
truth drawn for the catalog arm, carried by the chain of the URDF built from its DH table.
Identification time is the median wall time of `identify` per trial (say the machine's load with it).

How sure the ratio is: each trial's held-out mean square is a quadratic form δᵀAδ of the parameter
error δ ~ N(0, C) (A the held-out poses' mean J_vᵀJ_v), of variance 2·trace((AC)²); the "± 1σ" column
is the pooled ratio's predicted spread from it (a few directions of A·C carry each trial's error, so
one trial scatters by about ±45 % of its mean square, and ten trials by about ±7 % of the ratio).

Poses selected vs random at equal count: `bench/urdf_pose_selection.py`.

Run: python bench/any_arm.py [--trials 10] [--poses 40] [--seed 1]
"""

from __future__ import annotations

import argparse
import os
import time
from importlib import metadata
from pathlib import Path

import numpy as np

from hil.arm.chain import Robot
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics, identifiable_parameters
from hil.arm.urdf_chain import chain_from_text, chain_from_urdf
from hil.calibration.exports import to_urdf
from hil.calibration.identification import identify
from hil.calibration.measurements import Measurements
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from hil.calibration.tracker_noise import ANGLE_SIGMA, DISTANCE_SIGMA

_ROBOTS = "cmeel.prefix/share/example-robot-data/robots/"
#: name → (URDF below example-robot-data's robots directory, the link the SMR sits on)
ARMS = {
    "Franka Panda": ("panda_description/urdf/panda.urdf", "panda_link8"),
    "Kinova j2s6s200": ("kinova_description/robots/kinova.urdf", "j2s6s200_end_effector"),
    "Unitree Z1": ("z1_description/urdf/z1.urdf", "link06"),
}
NOISE = Noise(encoder_sigma=0.0)  # the tracker's distance-dependent model, exact joints
VALIDATION = 500


def _urdf(relative: str) -> Path:
    return Path(str(metadata.distribution("example-robot-data").locate_file(_ROBOTS + relative)))


def point_weights(points: np.ndarray) -> np.ndarray:
    """(N, 3, 3) inverse noise covariance of tracker-frame points (module docstring): the beam u, the
    horizontal direction h ⟂ u and the zenith direction u × h, each with its own σ."""
    d = np.linalg.norm(points, axis=1)
    u = points / d[:, None]
    h = np.cross([0.0, 0.0, 1.0], u)
    sin_v = np.linalg.norm(h, axis=1)
    h /= sin_v[:, None]
    v = np.cross(u, h)
    outer = lambda a: np.einsum("ni,nj->nij", a, a)  # noqa: E731
    return (outer(u) / DISTANCE_SIGMA**2 + outer(v) / ((d * ANGLE_SIGMA) ** 2)[:, None, None]
            + outer(h) / ((d * sin_v * ANGLE_SIGMA) ** 2)[:, None, None])


def trial(robot: Robot, poses: int, rng: np.random.Generator,
          prior: bool = True) -> tuple[float, float, float, float, Geometry, float]:
    """(held-out MS, Cramér–Rao MS, MS of the registered nominal, seconds, calibrated geometry, the
    held-out MS's predicted variance)."""
    truth = random_truth("ur5e" if robot == "ur5e-urdf" else robot, rng, rigid=True)
    if robot == "ur5e-urdf":  # the catalog arm's station, through the chain of its URDF
        robot = ur5e_urdf()
        truth = Geometry(truth.robot, truth.joints, truth.flange, truth.smr, truth.tracker, chain=robot)
    q = random_configurations(robot, poses, rng)
    _, p = measure(truth, q, NOISE, rng)
    meas = Measurements.from_arrays(q, p)
    t0 = time.perf_counter()
    fit = identify(meas, robot, prior=prior)
    seconds = time.perf_counter() - t0
    qv = random_configurations(robot, VALIDATION, rng)
    kin = Kinematics(truth)
    true_v = kin.points(qv)
    err = Kinematics(fit.geometry).points(qv) - true_v
    before = Kinematics(fit.baseline).points(qv) - true_v
    idx = identifiable_parameters(robot)
    J = kin.jacobian(q[fit.used], idx)
    information = np.einsum("nki,nkl,nlj->ij", J, point_weights(kin.points(q[fit.used])), J)
    C = np.linalg.inv(information)
    Jv = kin.jacobian(qv, idx)
    AC = np.einsum("nji,njk->ik", Jv, Jv) / len(qv) @ C
    cr = float(np.trace(AC))
    return (float(np.mean(np.sum(err**2, 1))), cr, float(np.mean(np.sum(before**2, 1))), seconds,
            fit.geometry, float(2.0 * np.trace(AC @ AC)))


def ur5e_urdf() -> Robot:
    """The UR5e's chain from the URDF hil writes for its nominal DH table."""
    return chain_from_text(to_urdf(Geometry.nominal("ur5e")), tip="tool0", source="ur5e.urdf")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=10)
    ap.add_argument("--poses", type=int, default=40)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--no-prior", action="store_true",
                    help="plain least squares (as hil identify --no-prior)")
    args = ap.parse_args()
    robots: dict[str, Robot] = {name: chain_from_urdf(_urdf(rel), tip=tip)
                                for name, (rel, tip) in ARMS.items()}
    robots["UR5e via URDF"] = "ur5e-urdf"
    robots["UR5e catalog"] = "ur5e"
    for robot in robots.values():
        identifiable_parameters(ur5e_urdf() if robot == "ur5e-urdf" else robot)  # warm the caches
    print(f"{args.poses} random poses, {args.trials} stations per arm (seed {args.seed}), 0.5 mm / 1 mrad "
          f"placement errors, AT960 noise model, {VALIDATION} held-out poses, "
          f"{'least squares' if args.no_prior else 'MAP fit'}; load {os.getloadavg()[0]:.2f}")
    print(f"{'arm':<17} | {'joints':>6} | {'params':>6} | {'before (mm)':>11} | {'held-out (µm)':>13} | "
          f"{'Cramér–Rao (µm)':>15} | {'ratio':>5} | {'± 1σ':>5} | {'time (ms)':>9}")
    print("-" * 112)
    models: dict[str, list[Geometry]] = {}
    for name, robot in robots.items():
        rng = np.random.default_rng(args.seed)  # every arm sees the same stream: the UR5e rows compare
        rows = [trial(robot, args.poses, rng, not args.no_prior) for _ in range(args.trials)]
        models[name] = [r[4] for r in rows]
        held, cr, before = (float(np.sqrt(np.mean([r[k] for r in rows]))) for k in range(3))
        ms = float(np.median([r[3] for r in rows])) * 1e3
        # the ratio's predicted relative spread: the pooled MS's relative σ, halved for the square root
        spread = 0.5 * float(np.sqrt(sum(r[5] for r in rows)) / sum(r[1] for r in rows)) * held / cr
        chain = ur5e_urdf() if robot == "ur5e-urdf" else robot
        dof = 6 if isinstance(chain, str) else chain.dof
        print(f"{name:<17} | {dof:>6} | {len(identifiable_parameters(chain)):>6} | {before * 1e3:>11.3f} | "
              f"{held * 1e6:>13.2f} | {cr * 1e6:>15.2f} | {held / cr:>5.2f} | {spread:>5.2f} | {ms:>9.1f}")
    Q = random_configurations("ur5e", VALIDATION, np.random.default_rng(99))
    gap = max(float(np.max(np.abs(Kinematics(a).points(Q) - Kinematics(b).points(Q))))
              for a, b in zip(models["UR5e via URDF"], models["UR5e catalog"], strict=True))
    print(f"UR5e via URDF vs catalog: largest difference of the calibrated models' predictions "
          f"{gap:.2e} m over {args.trials} stations × {VALIDATION} poses")


if __name__ == "__main__":
    main()
