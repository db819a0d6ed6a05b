"""The two instruments' clocks of a station: how their timestamps relate to the true time.

A laser tracker and a robot controller each stamp their samples on their own quartz clock. Moving,
every millisecond the two disagree costs a tool speed's worth of millimetres (0.25 mm at 0.25 m/s), so
a sweep must know the map between them. This module is the *truth* side: the simulators stamp their
samples by it (`mocks.emscon`, `mocks.ur`), the synthetic streams of `hil.calibration.synthetic_stream`
too, and a test or bench reads the true map `StationClocks.controller_from_tracker` to judge what
`hil.calibration.stream_join` estimated from the data alone.

One clock (`InstrumentClock`) stamps a sample taken at true time t (seconds of the simulator's reference
clock) as

    stamp = offset + (1 + drift_ppm·10⁻⁶)·(t + latency) + jitter,     jitter ~ N(0, jitter_s²)

— `latency` is how much later than the instant it describes a sample is stamped (the stamp is the
clock's reading at t + latency). Two such clocks give t_ctrl = a + (1 + d)·t_trk
(`StationClocks.controller_from_tracker`); a and the two latencies cannot be told apart by any data
(every sample of a stream is shifted alike), which is why the join estimates one offset and a fixed
latency is part of it.

Defaults (`StationClocks.realistic`), with where each figure comes from:

* **Controller** (UR e-series RTDE): the ``timestamp`` output is "time elapsed since the controller
  was started [s]" and the data come at the controller's 500 Hz (UR, "Real-Time Data Exchange (RTDE)
  Guide", universal-robots.com, the field table). So its offset is 0 at the controller's start. It
  counts 2 ms cycles, so its stamps carry no jitter of their own (0 s); its drift is its quartz's:
  typical crystal oscillators are specified at ±10–50 ppm (e.g. Epson's and Abracon's general-purpose
  kHz/MHz crystals: ±10, ±20, ±30, ±50 ppm frequency tolerance grades), so +20 ppm, an assumption
  inside that range. Its latency (the encoders' reading against the cycle's stamp) is taken as 0:
  UR publishes none, and it would add to the offset anyway.
* **Tracker** (Leica AT960 on emScon): up to 1000 points a second (AT960 datasheet: "data output rate
  1000 Hz"; emScon TPI continuous time mode, ``lTimeSeparation`` ≥ 1 ms), each stamped on the
  tracker's clock in whole seconds and microseconds (``MeasValueT.lTime1``/``lTime2``, ES_C_API_Def.h,
  docs/design.md, Facts: emScon TPI). Its offset is the tracker's own clock at the simulator's start:
  it has been on far longer than the controller run (hil takes 1234.5678 s, an assumption: any value
  does, the join's first guess comes from the data). Drift −15 ppm (a quartz of the same 10–50 ppm
  class, chosen with the opposite sign so the two drifts add: a relative drift of 35 ppm, 2.1 ms over a
  one-minute sweep). Jitter 5 µs (σ): the stamps have microsecond resolution and come from the
  instrument's hardware; Leica publishes no jitter figure, so 5 µs is an assumption a few times the
  resolution. Latency 0.5 ms: an assumption (Leica does not publish the AT960's internal delay in
  continuous mode); it matters only to the truth, not to the join, which cannot separate it.

`StationClocks.ideal` is every clock perfect: zero offset, drift, jitter and latency.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from hil.errors import InputError


@dataclass(frozen=True)
class InstrumentClock:
    """One instrument's clock against the true time (module docstring: the stamp's formula)."""

    offset_s: float = 0.0
    drift_ppm: float = 0.0
    jitter_s: float = 0.0
    latency_s: float = 0.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.offset_s) and abs(self.drift_ppm) <= 1e3 and 0.0 <= self.jitter_s <= 0.1
                and 0.0 <= self.latency_s <= 1.0):
            raise ValueError(f"clock out of range: {self} (|drift| ≤ 1000 ppm, jitter 0..0.1 s, "
                             "latency 0..1 s)")

    @property
    def rate(self) -> float:
        """Clock seconds per true second: 1 + drift."""
        return 1.0 + self.drift_ppm * 1e-6

    def reading(self, t: np.ndarray | float) -> np.ndarray:
        """The clock's reading at true time(s) `t`, without jitter."""
        return self.offset_s + self.rate * np.asarray(t, dtype=float)

    def stamps(self, t: np.ndarray | float, rng: np.random.Generator | None = None) -> np.ndarray:
        """Stamps of samples taken at true times `t`: the reading at t + latency, plus jitter drawn
        from `rng` (none without one or with zero jitter)."""
        t = np.asarray(t, dtype=float)
        out = self.reading(t + self.latency_s)
        if rng is not None and self.jitter_s > 0:
            out = out + rng.normal(0.0, self.jitter_s, t.shape)
        return out

    def true_time(self, stamp: np.ndarray | float) -> np.ndarray:
        """The true time a jitter-free stamp describes (the inverse of `stamps` without jitter)."""
        return (np.asarray(stamp, dtype=float) - self.offset_s) / self.rate - self.latency_s


@dataclass(frozen=True)
class ClockMap:
    """t_ctrl = offset_s + (1 + drift)·t_trk: where a tracker stamp falls on the controller's clock."""

    offset_s: float
    drift: float  # dimensionless; ppm = drift·10⁶

    @property
    def drift_ppm(self) -> float:
        return self.drift * 1e6

    def __call__(self, t_trk: np.ndarray | float) -> np.ndarray:
        return self.offset_s + (1.0 + self.drift) * np.asarray(t_trk, dtype=float)


@dataclass(frozen=True)
class StationClocks:
    """The tracker's and the controller's clocks of one (simulated) station."""

    tracker: InstrumentClock = field(default_factory=InstrumentClock)
    controller: InstrumentClock = field(default_factory=InstrumentClock)

    @classmethod
    def realistic(cls) -> StationClocks:
        """The defaults of the module docstring (each figure's source there)."""
        return cls(tracker=InstrumentClock(offset_s=1234.5678, drift_ppm=-15.0, jitter_s=5e-6,
                                           latency_s=5e-4),
                   controller=InstrumentClock(offset_s=0.0, drift_ppm=20.0, jitter_s=0.0, latency_s=0.0))

    @classmethod
    def ideal(cls) -> StationClocks:
        """Perfect clocks: every stamp is the true time."""
        return cls()

    def controller_from_tracker(self) -> ClockMap:
        """The true map of a (jitter-free) tracker stamp to the controller's stamp of the same instant.

        From the stamps' formula: t = (s_trk − o_trk)/r_trk − l_trk and s_ctrl = o_ctrl +
        r_ctrl·(t + l_ctrl), so 1 + d = r_ctrl/r_trk and a = o_ctrl + r_ctrl·(l_ctrl − l_trk) −
        (1 + d)·o_trk."""
        trk, ctrl = self.tracker, self.controller
        ratio = ctrl.rate / trk.rate
        return ClockMap(ctrl.offset_s + ctrl.rate * (ctrl.latency_s - trk.latency_s) - ratio * trk.offset_s,
                        ratio - 1.0)

    def to_dict(self) -> dict[str, Any]:
        """The JSON block a simulated station's truth carries (``clocks``)."""
        return {"tracker": asdict(self.tracker), "controller": asdict(self.controller)}

    @classmethod
    def from_dict(cls, data: Any, source: str = "clocks") -> StationClocks:
        """Read the ``clocks`` block; a bad one is an `InputError` naming the field."""
        if not isinstance(data, dict):
            raise InputError(f"{source}: expected an object with 'tracker' and 'controller'")
        clocks = {}
        for name in ("tracker", "controller"):
            block = data.get(name, {})
            if not isinstance(block, dict):
                raise InputError(f"{source}.{name}: expected an object")
            unknown = set(block) - set(InstrumentClock.__dataclass_fields__)
            if unknown:
                raise InputError(f"{source}.{name}: unknown field {sorted(unknown)[0]!r}")
            try:
                clocks[name] = InstrumentClock(**{k: float(v) for k, v in block.items()})
            except (TypeError, ValueError) as exc:
                raise InputError(f"{source}.{name}: {exc}") from None
        return cls(**clocks)
