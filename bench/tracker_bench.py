"""Figures of the trackers: time per measurement vs baud and samples; simulator noise vs spec.

Run from the repository root: ``PYTHONPATH=. python bench/tracker_bench.py``. Prints two tables.
Timing goes through the real driver and a paced pty (the simulator waits each byte's time on the
wire at the given baud, 8N1); noise statistics sample the instrument directly (no I/O).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from drivers.tracker import GeoComTracker, SerialConfig, TrackerConfig
from drivers.tracker.geometry import cartesian_to_polar, polar_to_cartesian
from mocks.geocom import GeoComInstrument, GeoComSimulator, InstrumentConfig, LinkConfig, SimulatorConfig
from mocks.geocom.noise import NoiseSpec, mpe_m
from mocks.geocom.target import StaticTarget


def time_per_measurement(baud: int, samples: int, repeats: int) -> tuple[float, float]:
    """Median and max seconds of `measure_point(samples)` over a pty paced at ``baud``."""
    sim = GeoComSimulator(
        StaticTarget(np.array([1.5, 2.5, 0.3])),
        SimulatorConfig(link=LinkConfig(baudrate=baud, max_chunk=16), serve_tcp=False),
    ).start()
    try:
        cfg = TrackerConfig(SerialConfig(str(sim.pty_path), baudrate=baud), timeout=5.0)
        with GeoComTracker(cfg) as tr:
            tr.measure_point(1)  # warm-up
            times = []
            for _ in range(repeats):
                t0 = time.perf_counter()
                tr.measure_point(samples)
                times.append(time.perf_counter() - t0)
    finally:
        sim.stop()
    return statistics.median(times), max(times)


def noise_statistics(distance: float, n: int, spec: NoiseSpec) -> dict[str, float]:
    """Empirical errors of ``n`` simulated readings of a point ``distance`` metres away."""
    true = np.array([distance * 0.6, distance * 0.8, 0.0]) + np.array([0.0, 0.0, 0.2])
    true *= distance / np.linalg.norm(true)
    inst = GeoComInstrument(StaticTarget(true), InstrumentConfig(noise=spec, seed=1, true_temperature_c=12.0))
    inst.handle_line(b"%R1Q,2008:8,1")
    hz0, v0, d0 = cartesian_to_polar(true)
    rows = []
    for _ in range(n):
        reply = inst.handle_line(b"%R1Q,2108:0,1")
        assert reply is not None
        rows.append([float(x) for x in reply.decode().split(":")[1].split(",")[1:4]])
    arr = np.array(rows)
    err3d = np.linalg.norm(polar_to_cartesian(arr[:, 0], arr[:, 1], arr[:, 2]) - true, axis=1)
    mpe = mpe_m(distance)
    return {
        "sd_d_um": float(np.std(arr[:, 2] - d0) * 1e6),
        "sd_hz_urad": float(np.std((arr[:, 0] - hz0 + np.pi) % (2 * np.pi) - np.pi) * 1e6),
        "sd_v_urad": float(np.std(arr[:, 1] - v0) * 1e6),
        "rms3d_um": float(np.sqrt(np.mean(err3d**2)) * 1e6),
        "median3d_um": float(np.median(err3d) * 1e6),
        "mpe_um": mpe * 1e6,
        "within_mpe": float(np.mean(err3d <= mpe)),
    }


def main() -> None:
    """Print both tables."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--noise-samples", type=int, default=20000)
    args = parser.parse_args()

    print("time per measure_point (driver + paced pty simulator; lock status + DoMeasure + N x GetSimpleMea)")
    print(f"{'baud':>8} {'samples':>8} {'median ms':>10} {'max ms':>8} {'ms/sample':>10}")
    for baud in (9600, 115200):
        for samples in (1, 10):
            med, worst = time_per_measurement(baud, samples, args.repeats)
            per_sample = med * 1e3 / samples
            print(f"{baud:>8} {samples:>8} {med * 1e3:>10.1f} {worst * 1e3:>8.1f} {per_sample:>10.1f}")

    spec = NoiseSpec()
    print()
    print(
        f"simulator noise vs spec (configured: sd distance {spec.distance_sigma_m * 1e6:.1f} um, "
        f"sd angles {spec.angle_sigma_rad * 1e6:.1f} urad; MPE = 15 um + 6 um/m; n={args.noise_samples})"
    )
    print(
        f"{'d [m]':>6} {'sd d um':>8} {'sd Hz urad':>10} {'sd V urad':>9} {'rms3d um':>9} "
        f"{'med3d um':>9} {'MPE um':>7} {'<=MPE':>6} {'med/MPE':>8}"
    )
    for d in (1.0, 2.0, 5.0, 10.0, 20.0):
        s = noise_statistics(d, args.noise_samples, spec)
        print(
            f"{d:>6.1f} {s['sd_d_um']:>8.2f} {s['sd_hz_urad']:>10.2f} {s['sd_v_urad']:>9.2f} "
            f"{s['rms3d_um']:>9.2f} {s['median3d_um']:>9.2f} {s['mpe_um']:>7.1f} {s['within_mpe']:>6.1%} "
            f"{s['median3d_um'] / s['mpe_um']:>8.2f}"
        )


if __name__ == "__main__":
    main()
