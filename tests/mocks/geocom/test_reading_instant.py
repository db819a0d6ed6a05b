"""A GeoCOM reading is of the instant its measuring time ends, not of when the instrument's thread woke."""

from __future__ import annotations

import numpy as np

from drivers.tracker.geometry import polar_to_cartesian
from mocks.geocom import NOISELESS, GeoComInstrument, InstrumentConfig
from mocks.geocom.target import TargetState

PROCESSING_S = 0.1


class MovingTarget:
    """An SMR moving along x at 1 m/s from (1, 2, 0.5), with a record of its past, as `mocks.world.World`."""

    def __init__(self) -> None:
        self.t = 10.0

    def _at(self, t: np.ndarray) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return np.column_stack([1.0 + (t - 10.0), np.full_like(t, 2.0), np.full_like(t, 0.5)])

    def target(self) -> TargetState:
        return TargetState(self._at(self.t)[0], True)

    def positions_at(self, times: np.ndarray, reading_time: float | None = None) -> np.ndarray:
        return self._at(times)

    def known_until(self) -> float:
        return self.t


def measure(late_by: float) -> np.ndarray:
    """One distance-and-angles reading whose sleep through the measuring time ends `late_by` s late."""
    source = MovingTarget()

    def sleep(seconds: float) -> None:
        source.t += seconds + late_by  # a loaded host wakes the thread late

    config = InstrumentConfig(noise=NOISELESS, true_temperature_c=12.0, processing_s=PROCESSING_S)
    inst = GeoComInstrument(source, config, sleep=sleep, now=lambda: source.t)
    assert inst.handle_line(b"%R1Q,2008,1:8,1") is not None  # tracking distance program
    reply = inst.handle_line(b"%R1Q,2108,2:100,1")
    assert reply is not None
    hz, v, d = (float(x) for x in reply.decode().split(":")[1].split(",")[1:4])
    return polar_to_cartesian(hz, v, d)


def test_a_late_wake_up_does_not_move_the_reading():
    on_time, late = measure(0.0), measure(0.35)
    expected = np.array([1.0 + PROCESSING_S, 2.0, 0.5])  # where the SMR was when the reading ended
    np.testing.assert_allclose(on_time, expected, atol=1e-9)
    np.testing.assert_allclose(late, expected, atol=1e-9)
