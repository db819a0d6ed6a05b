"""Benchmark (not a test): connect time, command round trip and servo-loop period jitter.

Runs the real ur_rtde client through the driver against a simulator process (or a real controller with
``--host``). Prints medians and 99th percentiles in milliseconds.

    python bench/robot_latency.py [--host ADDRESS] [--servo-steps 2000] [--roundtrips 200]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from drivers.robot import RobotConfig, URRobot
from mocks.ur.testing import start_sim


def _stats(xs: list[float]) -> str:
    a = np.asarray(xs) * 1e3
    return (f"median {np.median(a):.3f} ms, p99 {np.percentile(a, 99):.3f} ms, "
            f"max {a.max():.3f} ms (n={a.size})")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--host", help="a real controller or URSim; default: start a simulator")
    ap.add_argument("--servo-steps", type=int, default=2000)
    ap.add_argument("--roundtrips", type=int, default=200)
    args = ap.parse_args()
    sim = None if args.host else start_sim()
    host = args.host or sim.address  # type: ignore[union-attr]
    try:
        robot = URRobot(RobotConfig(host=host, speed=1.0, acceleration=2.0))
        connects = []
        for _ in range(3):
            t = time.perf_counter()
            robot.open()
            connects.append(time.perf_counter() - t)
            robot.close()
        print(f"connect (probe + dashboard + rtde_receive + rtde_control): {_stats(connects)}")
        robot.open()
        q0 = [0.2, -1.3, 1.3, -1.5, -1.5, 0.3]
        robot.move_to(q0)
        c = robot._c  # the benchmark measures the client itself
        rts = []
        for _ in range(args.roundtrips):
            t = time.perf_counter()
            c.isSteady()  # full command/ack handshake through the registers
            rts.append(time.perf_counter() - t)
        print(f"command round trip (isSteady): {_stats(rts)}")
        q = np.array(q0)
        with robot.servo(lookahead=0.1, gain=300) as stream:
            for i in range(args.servo_steps):
                stream.step(q + np.array([0.2, 0, 0, 0, 0, 0]) * np.sin(i / 500.0))
        periods = stream.periods
        dt = stream.dt
        jitter = [abs(p - dt) for p in periods]
        print(f"servo loop period (target {dt * 1e3:.1f} ms): {_stats(periods)}")
        print(f"servo loop jitter |period - target|: {_stats(jitter)}")
        robot.close()
    finally:
        if sim is not None:
            sim.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
