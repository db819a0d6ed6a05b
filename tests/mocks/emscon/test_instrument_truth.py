"""The emScon simulator samples the SMR where it truly was at each sample's time (issue 29).

A real tracker samples the true position at every instant. The simulator's server thread can be
starved on a loaded machine; when it only looked at the target on its own ticks, the samples of a
stall lay on the chord between two looks (a weld seam's corner measured 3 mm off). With a source
that keeps its past (the simulated station's world), a stall must delay samples, never move them.
"""

from __future__ import annotations

import numpy as np

from drivers.tracker.emscon.packets import Command, MultiMeasResult, decode_reply, encode_command
from mocks.emscon import EmsconConfig, EmsconInstrument
from mocks.geocom import NOISELESS
from mocks.geocom.target import TargetState

C = Command
CENTRE = np.array([3.0, 0.5, 0.2])
RADIUS = 0.05  # m
OMEGA = 2.0 * np.pi  # rad/s: one turn a second, 0.31 m/s


class CircleTarget:
    """An SMR running round a circle; it keeps its past, as `mocks.world.World` does, and knows the
    truth up to `known` (the arm's last recorded cycle), which the test sets."""

    def __init__(self) -> None:
        self.now = 0.0
        self.known: float | None = None
        self.epoch = 100.0  # the source's clock when the instrument's reads 0

    def _at(self, t: np.ndarray) -> np.ndarray:
        a = OMEGA * (np.asarray(t, float) - self.epoch)
        return CENTRE + RADIUS * np.column_stack([np.cos(a), np.sin(a), np.zeros_like(a)])

    def target(self) -> TargetState:
        return TargetState(self._at(np.array([self.now + self.epoch]))[0], True)

    def positions_at(self, times: np.ndarray, reading_time: float | None = None) -> np.ndarray:
        return self._at(times)

    def known_until(self) -> float | None:
        return self.known


def _streaming(source: CircleTarget) -> EmsconInstrument:
    inst = EmsconInstrument(source, EmsconConfig(noise=NOISELESS, find_s=0.0, failed_search_s=0.0))
    inst.source_epoch = source.epoch
    for command, params in ((C.INITIALIZE, ()), (C.SET_MEASUREMENT_MODE, (1,)),
                            (C.SET_CONTINUOUS_TIME_MODE_PARAMS, (10, 0, 0, 0)), (C.START_MEASUREMENT, ())):
        inst.handle(encode_command(command, *params), 0.0)
    return inst


def _samples(packets: list[bytes]) -> list[tuple[float, np.ndarray]]:
    out = []
    for p in packets:
        reply = decode_reply(p)
        if isinstance(reply, MultiMeasResult):
            out += [(s.seconds, np.array(s.position)) for s in reply.samples]
    return out


def test_a_starved_server_still_puts_every_sample_on_the_true_path() -> None:
    source = CircleTarget()
    inst = _streaming(source)
    got: list[tuple[float, np.ndarray]] = []
    for now in (0.01, 0.02, 0.03, 0.43, 0.44):  # the thread stalls 0.4 s after 0.03 s
        source.now, source.known = now, now + source.epoch
        got += _samples(inst.tick(now, flush=True, watch=False))
    times = np.array([t for t, _ in got])
    np.testing.assert_allclose(times, 0.01 * np.arange(45), atol=1e-6)  # none lost, none moved in time
    positions = np.array([p for _, p in got])
    np.testing.assert_allclose(positions, source.positions_at(times + source.epoch), atol=1e-9)
    # on the circle: a chord across the stall (0.4 of a turn) would be 19 mm inside it
    radius = np.linalg.norm(positions[:, :2] - CENTRE[:2], axis=1)
    np.testing.assert_allclose(radius, RADIUS, atol=1e-9)


def test_samples_the_source_cannot_tell_yet_wait_for_it() -> None:
    source = CircleTarget()
    inst = _streaming(source)
    source.now, source.known = 0.2, 0.05 + source.epoch  # the arm's thread is behind the tracker's
    early = _samples(inst.tick(0.2, flush=True))
    assert [round(t, 6) for t, _ in early] == [round(0.01 * k, 6) for k in range(6)]
    source.now, source.known = 0.21, 0.21 + source.epoch
    late = _samples(inst.tick(0.21, flush=True))
    times = np.array([t for t, _ in early + late])
    np.testing.assert_allclose(times, 0.01 * np.arange(22), atol=1e-6)
    positions = np.array([p for _, p in early + late])
    np.testing.assert_allclose(positions, source.positions_at(times + source.epoch), atol=1e-9)
