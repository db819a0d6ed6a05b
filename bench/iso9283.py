"""The ISO 9283 pose test on the simulated station: the controller's own model against hil's.

For each robot, a hidden truth (seeded) is written to a file and the simulated station runs it. hil's
model is identified from synthetic measurements of that same truth (`hil.calibration.synthetic`:
random visible poses, the tracker's 20 µm noise), as a calibration would find it, then
``hil verify --sim --truth T --model M`` measures AP and RP of P1–P5 uncompensated (the controller's
IK of each pose) and compensated (hil's model), in the model's frame and — for the uncompensated poses
— in the controller's own fitted frame. With the truth known, the controller's factory model (its
KinematicsInfo, as the simulated controller reported it in the result) and hil's model are also
compared with the truth over random workspace poses: RMS and max of the SMR position error, in the
truth's base frame and after fitting each model's own tracker frame (the frame no measurement fixes).

The simulated arm stops off each target by its datasheet repeatability (each joint's stop-to-stop
error, `hil.arm.joint_physics.standstill_sigma`: UR5e ±0.03 mm, UR10e ±0.05 mm RP of its own), written
in the truth's ``noise.standstill_sigma``; ``--no-standstill`` stops it exactly on every target (the
simulator before it had one), so RP is then the tracker's noise and the arm's ringing alone.

Run: python bench/iso9283.py [--robots ur5e,ur10e] [--cycles 30] [--speed 100] [--seed 7] [--no-standstill]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from hil.arm.controller_model import ControllerCalibration
from hil.arm.geometry import Geometry
from hil.arm.joint_physics import POSE_REPEATABILITY, standstill_sigma
from hil.arm.kinematics import Kinematics
from hil.calibration.identification import identify, register
from hil.calibration.measurements import Measurements
from hil.calibration.model_file import model_document, truth_document
from hil.calibration.synthetic import Noise, measure, random_truth
from hil.campaign.controller import controller_calibration
from hil.verify.cube import POSE_NAMES
from mocks.world import World

ROOT = Path(__file__).resolve().parents[1]


def visible(truth: Geometry, count: int, rng: np.random.Generator) -> np.ndarray:
    """Random configurations, upper arm up, whose SMR faces the tracker (within 30°)."""
    world = World(truth, lambda: np.zeros(6))
    out: list[np.ndarray] = []
    while len(out) < count:
        q = rng.uniform(-np.pi, np.pi, 6)
        q[1] = rng.uniform(-np.pi, 0.0)
        _, angle = world.state(q)
        if angle < 30.0 and Kinematics(truth).points(q, frame="base")[0][2] > 0.05:
            out.append(q)
    return np.array(out)


def identified_model(truth: Geometry, rng: np.random.Generator, poses: int = 40) -> dict:
    """hil's model of `truth`, identified from `poses` synthetic measurements (tracker noise 20 µm)."""
    q = visible(truth, poses, rng)
    q_read, p = measure(truth, q, Noise(), rng)
    fit = identify(Measurements.from_arrays(q_read, p, "synthetic"), truth.robot, np.array([0, 0, 0.045]))
    return model_document(fit)


def model_error(model: Geometry, truth: Geometry, q: np.ndarray) -> dict[str, float]:
    """SMR position error of `model` (its arm, the truth's SMR) against the truth at `q` (m): in the
    truth's base frame, and after fitting the model's own tracker frame and SMR to the true points."""
    arm = Geometry(model.robot, model.joints, model.flange, truth.smr, truth.tracker)
    true = Kinematics(truth).points(q, frame="base")
    raw = np.linalg.norm(Kinematics(arm).points(q, frame="base") - true, axis=1)
    meas = Measurements.from_arrays(q, Kinematics(truth).points(q), "truth")
    located = register(meas, truth.robot, truth.smr, arm=arm)
    fitted = np.linalg.norm(Kinematics(located).points(q) - meas.p, axis=1)
    return {"rms": float(np.sqrt(np.mean(raw**2))), "max": float(raw.max()),
            "rms_fitted": float(np.sqrt(np.mean(fitted**2))), "max_fitted": float(fitted.max())}


def run_verify(tmp: Path, robot: str, truth_file: Path, model_file: Path, args: argparse.Namespace) -> dict:
    out = tmp / f"{robot}-result.json"
    cmd = [sys.executable, "-m", "hil", "verify", "--sim", "--truth", str(truth_file), "--model",
           str(model_file), "--speed", str(args.speed), "--seed", str(args.seed),
           "--cycles", str(args.cycles), "--db", str(tmp / f"{robot}.db"), "--out", str(out)]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"hil verify failed ({done.returncode}): {done.stderr[-2000:]}")
    return json.loads(out.read_text())


def mm(v: float) -> str:
    return f"{v * 1e3:8.3f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--robots", default="ur5e,ur10e")
    ap.add_argument("--cycles", type=int, default=30)
    ap.add_argument("--speed", type=float, default=100.0)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--no-standstill", action="store_true",
                    help="joints stop exactly on their targets (no repeatability of the arm's own)")
    args = ap.parse_args()
    rows, models = [], []
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        for robot in args.robots.split(","):
            rng = np.random.default_rng(args.seed)
            truth = random_truth(robot, rng)
            truth_file, model_file = tmp / f"{robot}-truth.json", tmp / f"{robot}-model.json"
            stops = 0.0 if args.no_standstill else standstill_sigma(robot)
            truth_file.write_text(json.dumps(truth_document(truth, Noise(standstill_sigma=stops))))
            model_doc = identified_model(truth, rng)
            model_file.write_text(json.dumps(model_doc))
            doc = run_verify(tmp, robot, truth_file, model_file, args)
            for mode, block in doc["results"].items():
                rows.append((robot, mode, block))
            if "own_frame" in doc:
                rows.append((robot, "uncomp. (own frame)", doc["own_frame"]))
            q = visible(truth, 300, np.random.default_rng(args.seed + 1))
            reported = doc["controller"]
            calibration = (controller_calibration(reported) if reported.get("reported")
                           else ControllerCalibration())
            models.append((robot, "controller (factory)" + ("" if reported.get("reported") else ", nominal"),
                           model_error(calibration.geometry(robot), truth, q)))
            models.append((robot, "hil (identified)", model_error(Geometry.from_dict(model_doc), truth, q)))
    stops = ("joints stop exactly on their targets" if args.no_standstill else
             "joints stop off their targets by the datasheet repeatability (" + ", ".join(
                 f"{r} ±{POSE_REPEATABILITY[r] * 1e3:g} mm" for r in args.robots.split(",")) + ")")
    print(f"ISO 9283 pose test, simulated station, {args.cycles} cycles, speed {args.speed:g} (mm); {stops}")
    head = f"{'robot':<6} {'mode':<20}" + "".join(f"{'AP ' + n:>9}" for n in POSE_NAMES)
    print(head + f"{'AP max':>9}{'RP max':>9}")
    print("-" * (len(head) + 18))
    for robot, mode, block in rows:
        ap_by_pose = {p["pose"]: p.get("AP_P") for p in block["poses"]}
        cells = "".join(f"{mm(ap_by_pose[n]):>9}" if ap_by_pose.get(n) is not None else f"{'—':>9}"
                        for n in POSE_NAMES)
        print(f"{robot:<6} {mode:<20}{cells}{mm(block['AP_max']):>9}{mm(block['RP_max']):>9}")
    print()
    print("model vs truth over 300 random visible poses, SMR position error (mm)")
    print(f"{'robot':<6} {'model':<28}{'RMS':>9}{'max':>9}{'RMS fit':>9}{'max fit':>9}")
    print("-" * 70)
    for robot, name, e in models:
        print(f"{robot:<6} {name:<28}{mm(e['rms']):>9}{mm(e['max']):>9}{mm(e['rms_fitted']):>9}"
              f"{mm(e['max_fitted']):>9}")
    print("(RMS/max: in the truth's base frame; fit: after fitting the model's own tracker frame and SMR)")


if __name__ == "__main__":
    main()
