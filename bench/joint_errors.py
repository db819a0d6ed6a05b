"""Low-order joint errors: identifiability, the cross-validated choice, recovery, held-out truth error.

Usage: python bench/joint_errors.py [--seeds N] [--poses N]

Prints five tables:

1. how much of each harmonic column survives projection on the geometry's 27 identifiable columns
   (generic point, `hil.arm.kinematics.identifiable_joint_errors`), per robot;
2. how often the cross-validated forward selection keeps a term on a truth *without* joint errors (false
   positives) and finds the true groups on one *with* them, over seeds;
3. recovery of known low-order terms by a fit with fixed orders: each estimate's error over its σ;
4. held-out truth error (200 random poses, noise-free truth) of geometry + compliance alone and with the
   cross-validated joint errors, on an arm with this bench's realistic blocks, for a one-sided and a
   two-sided approach;
5. `identify_with_joint_errors` run time for 40 poses (median of the seeds).

The realistic blocks here are this bench's *assumption* beside the simulator's realistic truth
(`hil.arm.joint_physics`): per joint, harmonics of orders 1 and 2 with coefficients N(0, 50 µrad) and
N(0, 30 µrad),
a transmission-error ripple at 2·101 per turn (a strain-wave gear of ratio 101 — the Harmonic Drive
catalog's ratios are 50–160) of 10 µrad, and lost motion of 10–40 µrad. These sizes were chosen so that
the joint errors alone leave a calibrated UR5e at about a tenth of a millimetre, the order the real UR5
reaches (docs/design.md, Facts: what real arms reach), not taken from a measurement.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from hil.arm.blas_threads import limit_blas_threads
from hil.arm.catalog import ROBOT_NAMES
from hil.arm.joint_error_columns import term_groups
from hil.arm.joint_errors import JointErrors
from hil.arm.kinematics import (
    N_EXTENDED_PARAMETERS,
    Kinematics,
    generic_configurations,
    generic_geometry,
    identifiable_parameters,
)
from hil.calibration.identification import identify
from hil.calibration.joint_error_selection import (
    JointErrorRequest,
    candidate_groups,
    choose_terms,
    identify_with_joint_errors,
)
from hil.calibration.measurements import Measurements
from hil.calibration.synthetic import Noise, random_configurations, random_truth, smr_payload

#: The bench's assumed blocks (module docstring).
ORDER_SIGMA = {1: 50e-6, 2: 30e-6}
RIPPLE_ORDER, RIPPLE = 202, 10e-6
LOST_MOTION = (10e-6, 40e-6)


def realistic_blocks(rng: np.random.Generator) -> tuple[JointErrors, np.ndarray]:
    """This bench's joint errors and lost motion (module docstring: an assumption)."""
    joints = []
    for _ in range(6):
        terms = [[k, *rng.normal(0.0, s, 2)] for k, s in ORDER_SIGMA.items()]
        phase = rng.uniform(0, 2 * np.pi)
        terms.append([RIPPLE_ORDER, RIPPLE * np.cos(phase), RIPPLE * np.sin(phase)])
        joints.append(terms)
    return JointErrors.of(joints), rng.uniform(*LOST_MOTION, 6)


def station(robot: str, seed: int, poses: int, *, blocks: bool, rigid: bool = True,
            two_sided: bool = False):
    """(truth, measurements, held-out configurations): a truth with or without the assumed blocks."""
    rng = np.random.default_rng(seed)
    truth = random_truth(robot, rng, rigid=rigid)
    truth.thermal = None  # warm-up is the campaign's business, not this bench's
    if blocks:
        truth.joint_errors, truth.lost_motion = realistic_blocks(np.random.default_rng(10_000 + seed))
    q = random_configurations(robot, poses, rng)
    directions = rng.choice([-1.0, 1.0], q.shape) if two_sided else np.ones_like(q)
    p = Kinematics(truth).points(q, directions=directions) + rng.normal(0, 20e-6, (poses, 3))
    q_read = q + rng.normal(0, Noise().encoder_sigma, q.shape)
    meas = Measurements.from_arrays(q_read, p, directions=directions if two_sided else None)
    return truth, meas, random_configurations(robot, 200, rng)


def truth_error(truth, model, q_check: np.ndarray) -> float:
    """RMS (m) of the model's prediction against the noise-free truth (no lost motion: the band's
    middle), over `q_check`."""
    d = Kinematics(model).points(q_check) - Kinematics(truth).points(q_check)
    return float(np.sqrt(np.mean(np.sum(d * d, axis=1))))


def table_identifiability() -> None:
    print("1. harmonic column norm left after projecting out the geometry (unit columns, generic point)")
    print(f"{'robot':<6} {'k=1 j3,5,6':>12} {'k=1 j1,2,4':>12} {'k=2,3':>10}")
    groups = term_groups()
    for robot in ROBOT_NAMES:
        Q = generic_configurations(robot)
        J = Kinematics(generic_geometry(robot)).jacobian(Q, np.arange(N_EXTENDED_PARAMETERS))
        J = J.reshape(-1, N_EXTENDED_PARAMETERS)
        J = J / np.where(np.linalg.norm(J, axis=0) > 0, np.linalg.norm(J, axis=0), 1.0)
        basis, _ = np.linalg.qr(J[:, identifiable_parameters(robot)])
        left = {}
        for name, cols in groups.items():
            if name.startswith("joint"):
                c = J[:, list(cols)]
                left[name] = np.linalg.norm(c - basis @ (basis.T @ c), axis=0)
        a = np.concatenate([left[f"joint{j}.k1"] for j in (3, 5, 6)])
        b = np.concatenate([left[f"joint{j}.k1"] for j in (1, 2, 4)])
        c = np.concatenate([left[f"joint{j}.k{k}"] for j in range(1, 7) for k in (2, 3)])
        print(f"{robot:<6} {a.min():.2f}–{a.max():.2f}   {b.min():.2f}–{b.max():.2f}  "
              f"{c.min():.2f}–{c.max():.2f}")


def table_choice(seeds: int, poses: int) -> None:
    print(f"\n2. cross-validated choice, {poses} poses, UR5e, {seeds} seeds (geometry-only fit + selection)")
    for blocks in (False, True):
        kept, true_found, sizes = 0, 0, []
        for seed in range(seeds):
            _, meas, _ = station("UR5e", seed, poses, blocks=blocks)
            fit = identify(meas, "UR5e")
            choice = choose_terms(fit, meas, candidate_groups("UR5e", meas))
            kept += bool(choice.groups)
            sizes.append(len(choice.groups))
            if blocks:
                true_found += sum(g.endswith(("k1", "k2")) for g in choice.groups)
        what = "with the assumed blocks" if blocks else "rigid, no joint errors"
        extra = f", of them true (orders 1-2): {true_found}" if blocks else ""
        print(f"  {what:<26} fits keeping any term: {kept}/{seeds}; groups kept: "
              f"{sum(sizes)} (mean {np.mean(sizes):.1f}){extra}")


def table_recovery(poses: int = 120) -> None:
    print(f"\n3. recovery of known orders 1-2 (fixed orders 1,2; rigid UR5e, {poses} poses, no ripple)")
    rng = np.random.default_rng(5)
    truth = random_truth("UR5e", rng, rigid=True)
    terms = [[[k, *rng.normal(0.0, s, 2)] for k, s in ORDER_SIGMA.items()] for _ in range(6)]
    truth.joint_errors = JointErrors.of(terms)
    q = random_configurations("UR5e", poses, rng)
    p = Kinematics(truth).points(q) + rng.normal(0, 20e-6, (poses, 3))
    meas = Measurements.from_arrays(q + rng.normal(0, Noise().encoder_sigma, q.shape), p)
    fit = identify_with_joint_errors(meas, "UR5e", request=JointErrorRequest("orders", (1, 2)))
    z = []
    for name, v, s in zip(fit.names, fit.values, fit.std, strict=True):
        if ".cos" in name or ".sin" in name:
            j, rest = name.split(".")
            k = int(rest[3:])
            true = terms[int(j[5:]) - 1][k - 1][1 if rest.startswith("cos") else 2]
            z.append((v - true) / s)
            print(f"  {name:<12} true {true * 1e6:+7.1f}  fit {v * 1e6:+7.1f} ± {s * 1e6:4.1f} µrad  "
                  f"({(v - true) / s:+.1f} σ)")
    print(f"  largest |error| / σ: {np.max(np.abs(z)):.2f} over {len(z)} terms")


def table_truth_error(seeds: int, poses: int) -> None:
    print(f"\n4. held-out truth error (200 poses), realistic UR5e/UR10e (compliance + assumed blocks), "
          f"{poses} poses, {seeds} seeds, compliance identified in both")
    for robot in ("UR5e", "UR10e"):
        for two_sided in (False, True):
            rows = []
            for seed in range(seeds):
                truth, meas, q_check = station(robot, seed, poses, blocks=True, rigid=False,
                                               two_sided=two_sided)
                payload = smr_payload(truth.smr)
                none = identify_with_joint_errors(meas, robot, request=JointErrorRequest("none"),
                                                  compliance=True, payload=payload)
                auto = identify_with_joint_errors(meas, robot, compliance=True, payload=payload)
                rows.append((truth_error(truth, none.geometry, q_check),
                             truth_error(truth, auto.geometry, q_check), len(auto.joint_error_choice.groups),
                             auto.joint_error_choice.cv_rms_without, auto.joint_error_choice.cv_rms))
            r = np.array(rows)
            side = "two-sided (d1..d6)" if two_sided else "one-sided"
            print(f"  {robot:<6} {side:<19} geometry+compliance {r[:, 0].mean() * 1e3:.4f} mm → "
                  f"+ joint errors {r[:, 1].mean() * 1e3:.4f} mm (mean; groups kept {r[:, 2].mean():.1f}; "
                  f"CV RMS {r[:, 3].mean() * 1e3:.4f} → {r[:, 4].mean() * 1e3:.4f} mm)")


def table_time(seeds: int) -> None:
    rows = []
    for seed in range(seeds):
        _, meas, _ = station("UR5e", seed, 40, blocks=True)
        for request in (JointErrorRequest("none"), JointErrorRequest("auto")):
            t0, c0 = time.perf_counter(), time.process_time()
            fit = identify_with_joint_errors(meas, "UR5e", request=request)
            rows.append((request.mode, time.perf_counter() - t0, time.process_time() - c0,
                         0.0 if fit.joint_error_choice is None else fit.joint_error_choice.seconds))
    print("\n5. identify run time, 40 poses (UR5e, assumed blocks), median over "
          f"{seeds} seeds (wall / CPU; a loaded machine shows in the wall time)")
    for mode in ("none", "auto"):
        r = np.array([row[1:] for row in rows if row[0] == mode])
        print(f"  --joint-errors {mode:<5} wall {np.median(r[:, 0]) * 1e3:4.0f} ms  CPU "
              f"{np.median(r[:, 1]) * 1e3:4.0f} ms  (the selection itself {np.median(r[:, 2]) * 1e3:.0f} ms)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--poses", type=int, default=40)
    args = parser.parse_args()
    limit_blas_threads()
    table_identifiability()
    table_choice(args.seeds, args.poses)
    table_recovery()
    table_truth_error(max(3, args.seeds // 4), args.poses)
    table_truth_error(max(3, args.seeds // 4), 100)
    table_time(min(args.seeds, 10))


if __name__ == "__main__":
    main()
