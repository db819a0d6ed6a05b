"""Figures for the sweep mode's foundations: the stream join's clock estimate against the truth, and what a
sync error costs at each tool speed.

Run from the repository root: ``PYTHONPATH=. python bench/stream_sync.py`` (``--quick``: one seed, 10 s
sweeps). Synthetic sweeps (`hil.calibration.synthetic_stream`): a realistic simulated arm (compliant,
with joint errors) sweeps a smooth joint path for `--duration` seconds at an RMS tool speed; the
controller streams its joints at 500 Hz, the tracker its points at 1000 Hz with the AT960's noise, each
stamped on its own clock (`StationClocks.realistic`: 35 ppm apart, the tracker's stamps jittering
5 µs). The join (`hil.calibration.stream_join`) then estimates the map with a model of the arm:

* ``truth``: the model is the true arm (what the join can do at best: the residual is noise);
* ``calibrated``: the true arm with `--model-error` µm and twice as many µrad of error on every joint
  origin and the flange (default 20 µm / 40 µrad: tens of µm at the tool, about what a static
  calibration leaves) — the residual then carries a model error that follows the path, which the
  join's σ (white residual assumed) does not cover.

Table 1: the offset's error at the sweep's middle against its stated σ, the drift's, the worst sync
error over the sweep, the position error that costs at the sweep's RMS speed, the samples used per
second. Table 2: what a given sync error costs (v·Δt) at 0.1, 0.25 and 0.5 m/s, predicted and as the
join's residual shows it (the RMS residual's growth over the noise, true model).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pinocchio as pin

from hil.arm.dynamics import DynamicsModel, MovingArm
from hil.arm.geometry import Geometry
from hil.calibration.stream_clocks import ClockMap
from hil.calibration.stream_join import StreamJoin
from hil.calibration.synthetic import random_truth
from hil.calibration.synthetic_stream import sweep_streams

SPEEDS = (0.1, 0.25, 0.5)
SYNC_ERRORS_MS = (0.1, 0.5, 1.0, 2.0)


def calibrated_like(truth: Geometry, rng: np.random.Generator, error_m: float) -> Geometry:
    """The truth with σ `error_m` (m) and 2·error_m (rad) of error on every joint origin and the flange."""
    g = truth.copy()

    def kick() -> pin.SE3:
        return pin.exp6(np.r_[rng.normal(0, error_m, 3), rng.normal(0, 2 * error_m, 3)])

    g.joints = [M * kick() for M in g.joints]
    g.flange = g.flange * kick()
    return g


def rms(r: np.ndarray) -> float:
    ok = np.isfinite(r).all(axis=1)
    return float(np.sqrt(np.mean(np.sum(r[ok] ** 2, axis=1))))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", default="ur5e,ur10e")
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--duration", type=float, default=20.0)
    parser.add_argument("--model-error", type=float, default=20.0, help="µm (and 2× µrad) per origin")
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    seeds = 1 if args.quick else args.seeds
    duration = 10.0 if args.quick else args.duration

    print(f"Table 1: clock map from {duration:.0f} s sweeps vs the simulator's truth "
          "(err/σ: the error in units of the stated σ)")
    print(f"{'robot':6} {'seed':>4} {'v m/s':>5} {'model':10} {'offset err µs':>13} {'σ µs':>6} "
          f"{'err/σ':>6} {'drift err ppm':>13} {'σ ppm':>6} {'worst sync µs':>13} {'costs µm':>8} "
          f"{'rms µm':>7} {'used/s':>6} {'fit s':>5}")
    costs: dict[float, list[tuple[float, float, float]]] = {v: [] for v in SPEEDS}
    for robot in args.robots.split(","):
        for seed in range(seeds):
            truth = random_truth(robot, np.random.default_rng(100 + seed), ideal=False)
            models = {"truth": truth, "calibrated": calibrated_like(truth, np.random.default_rng(200 + seed),
                                                                    args.model_error * 1e-6)}
            for v in SPEEDS:
                s = sweep_streams(truth, tool_speed=v, duration=duration, seed=seed)
                want = s.clocks.controller_from_tracker()
                for name, model in models.items():
                    t0 = time.perf_counter()
                    join = StreamJoin(s.joints, s.tracker, MovingArm(model).points,
                                      DynamicsModel(model).acceleration_limit)
                    fit = join.fit()
                    took = time.perf_counter() - t0
                    err = float(fit.map(fit.t_ref) - want(fit.t_ref))
                    worst = float(np.abs(fit.map(s.tracker.t) - want(s.tracker.t)).max())
                    print(f"{robot:6} {seed:4d} {v:5.2f} {name:10} {err * 1e6:13.3f} "
                          f"{fit.sigma_at_ref_s * 1e6:6.3f} {err / fit.sigma_at_ref_s:6.1f} "
                          f"{(fit.drift - want.drift) * 1e6:13.3f} {fit.sigma_drift * 1e6:6.3f} "
                          f"{worst * 1e6:13.2f} {worst * s.tool_speed_rms * 1e6:8.2f} "
                          f"{fit.rms_m * 1e6:7.1f} {fit.used / duration:6.0f} {took:5.1f}")
                    if name == "truth":
                        right = rms(join.residuals(want))
                        for ms in SYNC_ERRORS_MS:
                            late = rms(join.residuals(ClockMap(want.offset_s + ms * 1e-3, want.drift)))
                            costs[v].append((ms, s.tool_speed_rms, float(np.sqrt(late**2 - right**2))))
    print()
    print("Table 2: position error a sync error costs (µm): predicted v_rms·Δt / shown by the residual")
    print(f"{'v m/s':>5} " + " ".join(f"{f'{ms:g} ms':>15}" for ms in SYNC_ERRORS_MS))
    for v in SPEEDS:
        cells = []
        for ms in SYNC_ERRORS_MS:
            rows = [(speed, shown) for m, speed, shown in costs[v] if m == ms]
            predicted = np.mean([speed * ms * 1e-3 for speed, _ in rows]) * 1e6
            shown = np.mean([sh for _, sh in rows]) * 1e6
            cells.append(f"{predicted:7.0f} /{shown:6.0f}")
        print(f"{v:5.2f} " + " ".join(f"{c:>15}" for c in cells))


if __name__ == "__main__":
    main()
