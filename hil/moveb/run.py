"""Running a MOVEB plan on the robot and measuring how well the arm follows it.

* The TCP is the SMR centre (the model's ``smr`` in the flange frame, rotation of the flange): what
  the tracker measures is then exactly the programmed point, and the program's tool Z axis is the
  flange Z axis, the SMR's opening (keep it facing the tracker).
* Joint targets come from the *calibrated* model when one is given (``--model``), so the
  calibration's effect shows in the measured path; without one, the nominal model. They are solved by
  `hil.compensation` (`Compensator`: the branch the controller's own model — the one it reports, else
  its nominal one — would take, then the accurate solution), the code that compensates programs, so a
  path and a program choose branches and refuse unreachable targets alike.
* The trajectory is solved for every controller sample before anything moves (an unreachable sample
  is an error naming its arc length), then the arm moves to the start and the whole trajectory is
  handed to the driver's `follow`, whose servo loop runs in the isolated robot client's process (a
  crash of ur_rtde on a dropped link is a ConnectionLost here), while a thread samples the tracker in
  continuous mode. Both sides time-stamp on the system-wide monotonic clock.
* Tracker points are brought into the base frame with the model's tracker pose. Without a model that
  pose is unknown, so it is registered: a rigid fit of the measured points to the commanded positions
  at the same times, refined by nearest-point iterations (ICP). The result says ``registered: true``;
  a rigid misplacement of the arm is then not seen.
* hil's own lateness (servo deadlines missed on a loaded machine) is measured from the send times
  and reported with the figures (`hil.moveb.stream_timing`), never folded silently into them.
* Path accuracy in the style of ISO 9283 and the share of the path it covers: `hil.moveb.accuracy`.
  A run whose measured points cover less than ``min_coverage`` of the path is reported as
  ``incomplete`` (exit code 1) with the largest unmeasured stretch named: its figures describe only
  the part the tracker saw.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from scipy.spatial import cKDTree

from drivers.tracker.during import stream_during
from hil.arm.controller_model import ControllerCalibration
from hil.arm.geometry import Geometry
from hil.arm.safety import check_target
from hil.compensation.paths import solve_joint_path
from hil.compensation.solve import Compensator
from hil.errors import HilError, InputError
from hil.files.quantities import quantity
from hil.moveb.accuracy import Coverage, coverage, distance_to_path, path_accuracy
from hil.moveb.joints import JointSpeedError, JointSpeeds, joint_speed_ceiling, retime
from hil.moveb.orientation import rotation_matrices
from hil.moveb.path_plan import Plan, Samples
from hil.moveb.program import Program
from hil.moveb.stream_timing import StreamTiming, stream_timing
from hil.moveb.timing import Limits

Box = tuple[np.ndarray, np.ndarray]  # keep-in box corners (base frame, m)
#: servoJ lookahead (s) and gain of a MOVEB stream (docs/design.md, Facts: streaming on UR)
LOOKAHEAD = 0.05
GAIN = 1000.0


def program_in_frame(program: Program, anchor: np.ndarray) -> Program:
    """The program moved rigidly so its first point's frame is `anchor` (4x4, mm)."""
    from hil.moveb.program import MovebPoint

    p0 = program.points[0]
    R0 = np.column_stack([p0.x_axis, np.cross(p0.z_axis, p0.x_axis), p0.z_axis])
    R = anchor[:3, :3] @ R0.T
    pts = tuple(MovebPoint(p.line, R @ (p.position - p0.position) + anchor[:3, 3], R @ p.z_axis,
                           R @ p.x_axis, p.d, p.e) for p in program.points)
    return Program(pts, program.source)


def facing_frame(program: Program, tracker: np.ndarray, reach: float, *, out: float = 0.5,
                 height: float = 0.3) -> np.ndarray:
    """The anchor (4x4, mm) that puts `program` in front of the robot, facing a tracker at `tracker`.

    The program's centre goes `out` × `reach` from the base towards the tracker (horizontally), `height`
    metres up, and its first point's tool Z axis points at the tracker: the SMR then faces it (within
    the program's own orientation changes) and the arm stays behind the SMR, out of the beam. For a
    station whose tracker position is known (the simulated one, or a model's tracker pose) and a
    program written without a cell in mind (``hil/moveb/examples``).
    """
    t = np.asarray(tracker, dtype=float)
    ahead = np.array([t[0], t[1], 0.0])
    norm = float(np.linalg.norm(ahead))
    ahead = ahead / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])
    centre = out * reach * ahead + np.array([0.0, 0.0, height])
    z = t - centre
    z /= np.linalg.norm(z)
    x = np.cross([0.0, 0.0, 1.0], z)
    x = x / np.linalg.norm(x) if np.linalg.norm(x) > 1e-9 else np.array([1.0, 0.0, 0.0])
    anchor = np.eye(4)
    anchor[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    # program_in_frame maps p -> R (p - p0) + anchor; choose the anchor so the centre lands there
    p0 = program.points[0]
    R0 = np.column_stack([p0.x_axis, np.cross(p0.z_axis, p0.x_axis), p0.z_axis])
    R = anchor[:3, :3] @ R0.T
    middle = 0.5 * (program.positions.min(axis=0) + program.positions.max(axis=0))
    anchor[:3, 3] = centre * 1e3 - R @ (middle - p0.position)
    return anchor


class NothingMeasured(HilError):
    """The tracker streamed, but saw the SMR at fewer than three points: a line-of-sight problem."""

    def __init__(self, lost: int) -> None:
        super().__init__(f"the tracker measured nothing during the motion ({lost} records lost): keep the "
                         "SMR facing the tracker with a clear line of sight along the whole path")
        self.lost = lost


def tool_targets(samples_pos_mm: np.ndarray, z: np.ndarray, x: np.ndarray, smr: np.ndarray) -> list[pin.SE3]:
    """Flange poses (metres) putting the SMR at the samples with the tool axes (rotation of the flange)."""
    R = rotation_matrices(np.asarray(z, float), np.asarray(x, float))
    t = np.asarray(samples_pos_mm, float) * 1e-3 - R @ np.asarray(smr, float)
    return [pin.SE3(Ri, ti) for Ri, ti in zip(R, t, strict=True)]


def _kabsch(A: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """R, t minimising |R·A + t − B|."""
    ca, cb = A.mean(axis=0), B.mean(axis=0)
    U, _, Vt = np.linalg.svd((A - ca).T @ (B - cb))
    S = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ S @ U.T
    return R, cb - R @ ca


def register(measured: np.ndarray, commanded_at_time: np.ndarray, path: np.ndarray,
             iterations: int = 20, *, start: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Measured points (tracker frame) in the base frame: the best rigid fit to the commanded path.

    Starts: the fit to the commanded positions at the same times, and `start` (R, t: where the points
    are believed to be, a model's tracker pose) when given. Each start is refined by nearest-point
    iterations (ICP), and the pose kept is the one — a start included — whose points lie closest to
    the path by the RMS of `distance_to_path`, the figure the run reports. A best fit is therefore
    never worse than `start` unfitted: ICP only finds a local minimum, and a start from mis-timed
    samples (a tracker clock off by a fraction of the cycle) had left a model's 0.06 mm as 25 mm.
    """
    tree = cKDTree(path)
    starts = [_kabsch(measured, commanded_at_time)]
    if start is not None:
        starts.append((np.asarray(start[0], float), np.asarray(start[1], float)))
    best, best_rms = measured, np.inf
    for R, t in starts:
        for k in range(iterations + 1):
            moved = measured @ R.T + t
            rms = float(np.sqrt(np.mean(distance_to_path(moved, path) ** 2)))
            if rms < best_rms:
                best, best_rms = moved, rms
            if k == iterations:
                break
            _, idx = tree.query(moved)
            R, t = _kabsch(measured, path[idx])
    return best


@dataclass
class RunResult:
    accuracy: dict[str, Any]
    cycle_time: float
    registered: bool
    lost: int
    joint_speeds: dict[str, Any]
    accuracy_registered: dict[str, Any] | None = None  # with a model: the same run, rigidly fitted
    measured: np.ndarray | None = None  # (N, 3) mm, in the frame `accuracy` was computed in
    path: np.ndarray | None = None  # (M, 3) mm, the commanded path
    path_s: np.ndarray | None = None  # (M,) mm, its arc lengths
    corners: np.ndarray | None = None  # (K, 3) mm, programmed interior points
    coverage: Coverage | None = None  # the stretches of the path the tracker measured
    stream: StreamTiming | None = None  # how hil's servo stream kept its deadlines


@dataclass(frozen=True)
class Trajectory:
    """The joint trajectory to stream: one row of `Q` per controller sample."""

    samples: Samples  # the tool path at the controller samples (mm, base frame)
    Q: np.ndarray  # (N, 6) rad
    rate_hz: float
    speeds: JointSpeeds

    @property
    def cycle_time(self) -> float:
        return (len(self.Q) - 1) / self.rate_hz


def solve_trajectory(plan: Plan, geometry: Geometry, limits: Limits, rate_hz: float, q_start: np.ndarray,
                     *, joint_speed_fraction: float = 1.0, joint_acceleration: float | None = None,
                     keep_in: Box | None = None, grid_step: float = 1.0,
                     controller: Geometry | None = None) -> Trajectory:
    """Time the plan under the Cartesian limits *and* the joint speed maxima, and solve its IK.

    1. Every controller sample must lie in the keep-in box (checked on the dense path first, so a
       program that leaves it is refused before any IK).
    2. IK on a geometric grid (`grid_step` mm, and through every bridge) gives the joint-speed
       ceiling (`hil.moveb.joints`); the feed profile runs under it.
    3. IK at every controller sample (seeded from the grid's start, so both follow one branch), and
       the joint speeds checked against ``joint_speed_fraction`` × the datasheet maxima, retimed
       locally where the finite grid let a sample exceed them; likewise ``joint_acceleration``
       (rad/s², every joint) when given.

    `controller`: the controller's own model (its reported calibration), which picks the branch;
    its nominal model when None.
    """
    quantity("fraction").check(float(joint_speed_fraction), "joint speed fraction")
    if joint_acceleration is not None:
        quantity("joint acceleration").check(float(joint_acceleration), "joint acceleration")
    compensator = Compensator(geometry, controller or ControllerCalibration().geometry(geometry.spec))
    source = plan.program.source
    if keep_in is not None:
        lo, hi = (np.asarray(v, float) * 1e3 for v in keep_in)
        dense = plan.dense(min(grid_step, 0.5))
        out = np.flatnonzero(np.any((dense.position < lo) | (dense.position > hi), axis=1))
        if out.size:
            p = dense.position[out[0]]
            raise InputError(f"{source}: s = {dense.s[out[0]]:.1f} mm: the path leaves the keep-in box at "
                             f"({p[0]:.1f}, {p[1]:.1f}, {p[2]:.1f}) mm")
    geo = plan.at(plan.sample_grid(grid_step, per_bridge=16))
    Q_geo = solve_joint_path(compensator, tool_targets(geo.position, geo.z_axis, geo.x_axis, geometry.smr),
                             q_start, max_step=0.1, where=[f"{source}: s = {v:.1f} mm" for v in geo.s])
    allowed = joint_speed_fraction * geometry.spec.max_joint_speed
    ceiling = joint_speed_ceiling(geo.s, Q_geo, allowed)
    timed: dict[str, Samples] = {}

    def time_path(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        _law, samples = plan.timed(limits, rate_hz, ceiling=(geo.s, c))
        timed["samples"] = samples
        Q = solve_joint_path(compensator, tool_targets(samples.position, samples.z_axis, samples.x_axis,
                                                       geometry.smr),
                             Q_geo[0], where=[f"{source}: s = {v:.1f} mm" for v in samples.s])
        return samples.s, Q

    acc = None if joint_acceleration is None else np.full(6, float(joint_acceleration))
    try:
        Q, speeds = retime(time_path, geo.s, ceiling, rate_hz, allowed, allowed_acceleration=acc)
    except JointSpeedError as exc:
        raise JointSpeedError(f"{source}: {exc}") from None
    return Trajectory(timed["samples"], Q, rate_hz, speeds)


def reported_controller(info: Any, robot: str) -> Geometry | None:
    """The controller's own model from what its driver reported on connecting (its KinematicsInfo,
    ``info.kinematics``), or None when it reported none."""
    kinematics = getattr(info, "kinematics", None)
    if kinematics is None:
        return None
    return ControllerCalibration.from_dh(robot, *kinematics.dh()).geometry(robot)


def execute(devices: Any, plan: Plan, geometry: Geometry, limits: Limits, *, registered: bool,
            tracker_rate: float = 100.0, settle: float = 0.3, joint_speed_fraction: float = 1.0,
            joint_acceleration: float | None = None, keep_in: Box | None = None) -> RunResult:
    """Solve, move to the start, stream the samples and measure (see module docstring)."""
    rate = devices.robot.info.rate_hz if devices.robot.info else geometry.spec.rate_hz
    q_now = np.asarray(devices.robot.read_joints(1).q, dtype=float)
    traj = solve_trajectory(plan, geometry, limits, rate, q_now, joint_speed_fraction=joint_speed_fraction,
                            joint_acceleration=joint_acceleration, keep_in=keep_in,
                            controller=reported_controller(devices.robot.info, geometry.robot))
    samples, Q = traj.samples, traj.Q
    # the approach is a joint move: its path must stay in the keep-in box too (never clamped)
    check_target(Q[0], geometry.spec, keep_in, geometry, start=q_now)
    devices.robot.move_to(Q[0])
    records, res = stream_during(
        devices.tracker, tracker_rate,
        lambda: devices.robot.follow(Q, lookahead=LOOKAHEAD, gain=GAIN, settle=settle),
        lead_s=0.05, join_s=5.0)
    step_times = res.times  # send time of each sample (time.monotonic, as the tracker's records)
    timing = stream_timing(step_times, rate, LOOKAHEAD, samples.position)
    t0, t1 = step_times[0], step_times[-1] + settle
    during = [r for r in records if t0 <= r.t <= t1]
    measured = np.array([r.position is not None for r in during], dtype=bool)
    got = [r for r, ok in zip(during, measured, strict=True) if ok]
    lost = len(during) - len(got)
    if not during:  # not a single record while the arm moved: the tracker itself failed
        from drivers.tracker.errors import TrackerError

        raise TrackerError("the tracker sent no samples during the motion")
    if len(got) < 3:  # it streamed but could not see the SMR: where it stands, not a fault
        raise NothingMeasured(lost)
    m = np.array([r.position for r in got]) * 1e3  # mm, tracker frame
    dense = plan.dense(0.2)
    path = dense.position  # mm, base frame
    corners = plan.program.positions[1:-1]
    at = np.clip(np.searchsorted(step_times, [r.t for r in during]), 0, len(Q) - 1)  # sample per record
    cov = coverage(samples.s[at], measured, plan.length)
    corner_s = dense.s[cKDTree(path).query(corners)[1]] if len(corners) else np.zeros(0)
    seen = dict(corner_covered=cov.covers(corner_s), covered=cov.fraction, commanded_s=dense.s)
    shown = dict(path=path, path_s=dense.s, corners=corners, coverage=cov)
    T = geometry.tracker
    # with a model its tracker pose is one start of the fit: a best fit is never worse than none
    moved = register(m, samples.position[at[measured]], path,
                     start=None if registered else (T.rotation, T.translation * 1e3))
    fitted = path_accuracy(path, moved, corners, **seen)
    if registered:
        return RunResult(fitted, traj.cycle_time, True, lost, traj.speeds.as_dict(), None, moved, **shown,
                         stream=timing)
    base = m @ T.rotation.T + T.translation * 1e3
    # with a model: in its base frame, and (comparable with a run without one) rigidly fitted
    return RunResult(path_accuracy(path, base, corners, **seen), traj.cycle_time, False, lost,
                     traj.speeds.as_dict(), fitted, base, **shown, stream=timing)
