"""Running a MOVEB plan on the robot and measuring how well the arm follows it.

* The TCP is the SMR centre (the model's ``smr`` in the flange frame, rotation of the flange): what
  the tracker measures is then exactly the programmed point, and the program's tool Z axis is the
  flange Z axis, the SMR's opening (keep it facing the tracker).
* Joint targets come from `hil.ik` on the *calibrated* model when one is given (``--model``), so the
  calibration's effect shows in the measured path; without one, the nominal model.
* The trajectory is solved for every controller sample before anything moves (an unreachable sample
  is an error naming its arc length), then the arm moves to the start and the whole trajectory is
  handed to the driver's `follow`, whose servo loop runs in the isolated robot client's process (a
  crash of ur_rtde on a dropped link is a ConnectionLost here), while a thread samples the tracker in
  continuous mode. Both sides time-stamp on the system-wide monotonic clock.
* Tracker points are brought into the base frame with the model's tracker pose. Without a model that
  pose is unknown, so it is registered: a rigid fit of the measured points to the commanded positions
  at the same times, refined by nearest-point iterations (ICP). The result says ``registered: true``;
  a rigid misplacement of the arm is then not seen.
* Path accuracy in the style of ISO 9283 (path accuracy AT): for every measured point during the
  motion, its distance to the commanded path (the dense commanded polyline); max and RMS of those;
  and the corner deviation: for every interior program point, its distance to the measured path and
  to the commanded path.
"""

from __future__ import annotations

import argparse
import threading
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from scipy.spatial import cKDTree

from hil.geometry import Geometry
from hil.ik import solve_path
from hil.kinematics import Kinematics
from hil.moveb.plan import Plan, plan_program
from hil.moveb.program import Program, load_program
from hil.moveb.timing import Limits


def program_in_frame(program: Program, anchor: np.ndarray) -> Program:
    """The program moved rigidly so its first point's frame is `anchor` (4x4, mm)."""
    from hil.moveb.program import MovebPoint

    p0 = program.points[0]
    R0 = np.column_stack([p0.x_axis, np.cross(p0.z_axis, p0.x_axis), p0.z_axis])
    R = anchor[:3, :3] @ R0.T
    pts = tuple(MovebPoint(p.line, R @ (p.position - p0.position) + anchor[:3, 3], R @ p.z_axis,
                           R @ p.x_axis, p.d, p.e) for p in program.points)
    return Program(pts, program.source)


def tool_targets(samples_pos_mm: np.ndarray, z: np.ndarray, x: np.ndarray, smr: np.ndarray) -> list[pin.SE3]:
    """Flange poses (metres) putting the SMR at the samples with the tool axes (rotation of the flange)."""
    out = []
    for p, zz, xx in zip(samples_pos_mm, z, x, strict=True):
        R = np.column_stack([xx, np.cross(zz, xx), zz])
        out.append(pin.SE3(R, p * 1e-3 - R @ smr))
    return out


def _kabsch(A: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """R, t minimising |R·A + t − B|."""
    ca, cb = A.mean(axis=0), B.mean(axis=0)
    U, _, Vt = np.linalg.svd((A - ca).T @ (B - cb))
    S = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ S @ U.T
    return R, cb - R @ ca


def register(measured: np.ndarray, commanded_at_time: np.ndarray, path: np.ndarray,
             iterations: int = 20) -> np.ndarray:
    """Measured points (tracker frame) in the base frame by time-matched fit + nearest-point ICP."""
    R, t = _kabsch(measured, commanded_at_time)
    tree = cKDTree(path)
    for _ in range(iterations):
        moved = measured @ R.T + t
        _, idx = tree.query(moved)
        R, t = _kabsch(measured, path[idx])
    return measured @ R.T + t


def distance_to_path(points: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Distance of each point to the polyline `path` (nearest vertex, then its two segments)."""
    _, idx = cKDTree(path).query(points)
    best = np.full(len(points), np.inf)
    for off in (-1, 0):
        j = np.clip(idx + off, 0, len(path) - 2)
        a, b = path[j], path[j + 1]
        ab = b - a
        t = np.clip(np.einsum("ij,ij->i", points - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab),
                                                                        1e-300), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(points - (a + t[:, None] * ab), axis=1))
    return best


def path_accuracy(commanded: np.ndarray, measured: np.ndarray, corners: np.ndarray) -> dict[str, Any]:
    """ISO 9283-style figures in mm: AT max/RMS and the corner deviations (see module docstring)."""
    dev = distance_to_path(measured, commanded)
    return {"samples": len(measured), "max_deviation_mm": float(dev.max()),
            "rms_deviation_mm": float(np.sqrt(np.mean(dev ** 2))),
            "corner_deviation_measured_mm": distance_to_path(corners, measured).tolist()
            if len(corners) and len(measured) > 1 else [],
            "corner_deviation_commanded_mm": distance_to_path(corners, commanded).tolist()
            if len(corners) else []}


@dataclass
class RunResult:
    accuracy: dict[str, Any]
    cycle_time: float
    registered: bool
    lost: int


def execute(devices: Any, plan: Plan, geometry: Geometry, limits: Limits, *, registered: bool,
            tracker_rate: float = 100.0, settle: float = 0.3) -> RunResult:
    """Solve, move to the start, stream the samples and measure (see module docstring)."""
    rate = devices.robot.info.rate_hz if devices.robot.info else geometry.spec.rate_hz
    law, samples = plan.timed(limits, rate)
    kin = Kinematics(geometry)
    q_now = np.asarray(devices.robot.read_joints(1).q, dtype=float)
    where = [f"{plan.program.source}: s = {s:.1f} mm" for s in samples.s]
    Q = solve_path(kin, tool_targets(samples.position, samples.z_axis, samples.x_axis, geometry.smr),
                   q_now, where=where)
    devices.robot.move_to(Q[0])
    records: list[Any] = []
    stop = threading.Event()
    failure: list[BaseException] = []

    def sample() -> None:
        try:
            for rec in devices.tracker.stream(tracker_rate, stop=stop):
                records.append(rec)
        except BaseException as exc:  # reported after the motion
            failure.append(exc)

    thread = threading.Thread(target=sample, name="tracker-stream", daemon=True)
    thread.start()
    time.sleep(0.05)
    res = devices.robot.follow(Q, lookahead=0.05, gain=1000, settle=settle)
    step_times = res.times  # send time of each sample (time.monotonic, as the tracker's records)
    stop.set()
    thread.join(timeout=5.0)
    if failure:
        raise failure[0]
    t0, t1 = step_times[0], step_times[-1] + settle
    got = [r for r in records if r.position is not None and t0 <= r.t <= t1]
    lost = sum(1 for r in records if r.position is None and t0 <= r.t <= t1)
    if len(got) < 3:
        raise RuntimeError(f"the tracker returned {len(got)} points during the motion ({lost} lost)")
    m = np.array([r.position for r in got])
    path = plan.dense(0.2).position  # mm, base frame
    if registered:
        idx = np.clip(np.searchsorted(step_times, [r.t for r in got]), 0, len(Q) - 1)
        base = register(m * 1e3, samples.position[idx], path)
    else:
        T = geometry.tracker
        base = (m @ T.rotation.T + T.translation) * 1e3
    corners = plan.program.positions[1:-1]
    return RunResult(path_accuracy(path, base, corners), law.cycle_time, registered, lost)


def run_from_cli(args: argparse.Namespace) -> dict[str, Any]:
    """`hil moveb run`: station from --config/--sim (as `hil calibrate`), plan, execute, report."""
    from hil.cli.calibrate import _station
    from hil.errors import InputError
    from hil.model_file import load_geometry
    from hil.station import HARDWARE_ERRORS, open_devices

    program = load_program(args.program)
    limits = Limits(args.velocity, args.acceleration, args.jerk, args.normal_acceleration)
    if not args.tracker_rate > 0:
        raise InputError(f"--tracker-rate must be positive, got {args.tracker_rate}")
    model = load_geometry(args.model)[0] if args.model else None
    for name in ("poses", "validation", "candidates", "accept"):  # what `_station` reads for calibrate
        setattr(args, name, None)
    args.cycles = 1
    with _station(args) as (config, _identity, _truth):
        geometry = model or Geometry.nominal(config.robot["type"], smr=config.smr["offset"])
        try:
            devices = open_devices(config)
        except HARDWARE_ERRORS as exc:
            return {"status": "hardware fault", "error": f"{type(exc).__name__}: {exc}", "exit_code": 3}
        try:
            if args.frame == "current":
                q = np.asarray(devices.robot.read_joints(1).q, dtype=float)
                F = Kinematics(geometry).flange_poses(q)[0]
                anchor = F.copy()
                anchor[:3, 3] = (F[:3, :3] @ geometry.smr + F[:3, 3]) * 1e3
                program = program_in_frame(program, anchor)
            plan = plan_program(program, args.continuity)
            result = execute(devices, plan, geometry, limits, registered=model is None,
                             tracker_rate=args.tracker_rate)
        except HARDWARE_ERRORS as exc:
            return {"status": "hardware fault", "error": f"{type(exc).__name__}: {exc}", "exit_code": 3}
        finally:
            devices.close()
    return {"format": "hil-moveb-run/1", "status": "done", "exit_code": 0, "program": args.program,
            "continuity": args.continuity, "model": args.model, "registered": result.registered,
            "cycle_time_s": result.cycle_time, "lost_samples": result.lost,
            "path_accuracy": result.accuracy}
