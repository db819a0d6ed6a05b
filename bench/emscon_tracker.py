"""emScon TPI through the simulator: point round trip and continuous-mode sample rate.

Run from the repository root: ``PYTHONPATH=. python bench/emscon_tracker.py``. Prints two tables.
The driver (`drivers.tracker.emscon.EmsconTracker`) talks TCP on loopback to the simulated AT960
(`mocks.emscon`), which runs at real time here (time scale 1), so the measuring time the tracker
averages over is spent for real; "overhead" is what the protocol and both ends add to it. The GeoCOM
driver over TCP (no baud pacing) is timed beside it for reference.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from drivers.tracker import (
    EmsconConfig,
    EmsconTracker,
    GeoComTracker,
    SerialConfig,
    TcpConfig,
    TrackerConfig,
)
from mocks.emscon.instrument import EmsconConfig as SimConfig
from mocks.emscon.server import EmsconSimulator, ServerConfig
from mocks.geocom import GeoComSimulator, SimulatorConfig
from mocks.geocom.target import StaticTarget

TRUTH = np.array([2.5, 1.0, 0.4])


def _simulator() -> EmsconSimulator:
    """The simulated AT960 at real time (its measuring time is spent for real)."""
    config = ServerConfig(instrument=SimConfig(), time_scale=1.0)
    return EmsconSimulator(StaticTarget(TRUTH.copy()), config).start()


def emscon_points(measure_ms: int, repeats: int) -> list[float]:
    sim = _simulator()
    try:
        cfg = EmsconConfig(TcpConfig(sim.url), measure_time_ms=measure_ms, timeout=5.0)
        with EmsconTracker(cfg) as tr:
            tr.measure_point(1)  # warm-up
            times = []
            for _ in range(repeats):
                t0 = time.perf_counter()
                tr.measure_point(1)
                times.append(time.perf_counter() - t0)
    finally:
        sim.stop()
    return times


def geocom_points(samples: int, repeats: int) -> list[float]:
    sim = GeoComSimulator(StaticTarget(TRUTH.copy()), SimulatorConfig()).start()
    try:
        with GeoComTracker(TrackerConfig(SerialConfig(sim.url), timeout=5.0)) as tr:
            tr.measure_point(samples)
            times = []
            for _ in range(repeats):
                t0 = time.perf_counter()
                tr.measure_point(samples)
                times.append(time.perf_counter() - t0)
    finally:
        sim.stop()
    return times


def emscon_stream(rate_hz: float, seconds: float) -> dict[str, float]:
    sim = _simulator()
    try:
        with EmsconTracker(EmsconConfig(TcpConfig(sim.url), timeout=5.0)) as tr:
            arrivals, stamps = [], []
            t0 = time.monotonic()
            for s in tr.stream(rate_hz, duration=seconds):
                arrivals.append(time.monotonic())
                stamps.append(s.t)
            elapsed = time.monotonic() - t0
    finally:
        sim.stop()
    a, t = np.array(arrivals), np.array(stamps)
    gaps = np.diff(a)
    packets = int(np.sum(gaps > 0.02)) + 1  # samples of one packet arrive together
    return {"samples": len(t), "rate": len(t) / elapsed, "packets_s": packets / elapsed,
            "spacing_ms": float(np.median(np.diff(t)) * 1e3),
            "age_ms": float(np.median(a - t) * 1e3), "age_max_ms": float(np.max(a - t) * 1e3)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--seconds", type=float, default=3.0)
    args = parser.parse_args()

    print("point round trip: measure_point(1), loopback TCP, simulator at real time")
    print(f"{'driver':<10} {'measuring':>12} {'median ms':>10} {'min ms':>8} {'max ms':>8} "
          f"{'overhead ms':>12}")
    for ms in (1, 100, 500):
        times = emscon_points(ms, args.repeats)
        med = statistics.median(times) * 1e3
        print(f"{'emScon':<10} {f'{ms} ms':>12} {med:>10.1f} {min(times) * 1e3:>8.1f} "
              f"{max(times) * 1e3:>8.1f} {med - ms:>12.1f}")
    for samples in (1, 5):
        times = geocom_points(samples, args.repeats)
        med = statistics.median(times) * 1e3
        print(f"{'GeoCOM':<10} {f'{samples} sample(s)':>12} {med:>10.1f} {min(times) * 1e3:>8.1f} "
              f"{max(times) * 1e3:>8.1f} {'-':>12}")

    print()
    print(f"continuous time mode through the simulator, {args.seconds:.0f} s per rate (samples reach the "
          "caller in packets of about 100 ms, emScon's TcpDataPacketRate)")
    print(f"{'asked Hz':>9} {'samples':>8} {'got /s':>8} {'packets/s':>10} {'spacing ms':>11} "
          f"{'age ms':>7} {'age max':>8}")
    for rate in (100.0, 500.0, 1000.0):
        r = emscon_stream(rate, args.seconds)
        print(f"{rate:>9.0f} {r['samples']:>8} {r['rate']:>8.1f} {r['packets_s']:>10.1f} "
              f"{r['spacing_ms']:>11.3f} {r['age_ms']:>7.1f} {r['age_max_ms']:>8.1f}")


if __name__ == "__main__":
    main()
