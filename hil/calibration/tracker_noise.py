"""A laser tracker's measurement error, growing with distance: the one model the simulators share.

Leica's datasheet for the Absolute Tracker AT960 states the maximum permissible error of a point as
U_xyz = ±(15 µm + 6 µm/m) (Leica Geosystems, "Leica Absolute Tracker AT960" product brochure, technical
data, accuracy per ISO 10360-10), and "typical" as about half of it. We read the MPE as about 2σ and
split it as the instrument errs: a constant part along the beam (the interferometer/ADM distance:
σ = 15/2 = 7.5 µm) and a part across it that grows with distance (the angle encoders: σ = 6/2 = 3 µrad
on the horizontal and on the zenith angle, 3 µm per metre). A point 3 m away then scatters by 7.5 µm
along the beam and 9 µm across it per axis; at 10 m by 30 µm across it.

The GeoCOM and emScon simulators (`mocks.geocom.noise`) perturb the angles and the distance they
report with these figures, and offline synthetic measurements (`hil.calibration.synthetic.Noise`,
``hil synth``) perturb points the same way through the same function, so a simulated station and an
offline data set have one error model. Angles use `drivers.tracker.geometry`'s convention (the one
polar ↔ Cartesian conversion).
"""

from __future__ import annotations

import numpy as np

from drivers.tracker.geometry import cartesian_to_polar, polar_to_cartesian

#: The AT960's MPE, constant part (m) and part proportional to the distance (m per m): module docstring.
MPE_CONSTANT = 15e-6
MPE_PROPORTIONAL = 6e-6
#: 1-σ of one reading, the MPE read as 2σ: along the beam (m) and of each angle (rad).
DISTANCE_SIGMA = MPE_CONSTANT / 2
ANGLE_SIGMA = MPE_PROPORTIONAL / 2


def mpe_m(distance_m: float, constant_m: float = MPE_CONSTANT,
          proportional: float = MPE_PROPORTIONAL) -> float:
    """Maximum permissible error (m) of a point at `distance_m` metres from the tracker."""
    return constant_m + proportional * distance_m


def perturb_polar(hz: float, v: float, d: float, rng: np.random.Generator,
                  distance_sigma: float = DISTANCE_SIGMA,
                  angle_sigma: float = ANGLE_SIGMA) -> tuple[float, float, float]:
    """One noisy reading (hz, v, d) around the true one: each angle with `angle_sigma`, the distance
    with `distance_sigma` (drawn in that order); hz kept in [0, 2π)."""
    e_hz, e_v = rng.normal(0.0, angle_sigma, 2)
    e_d = rng.normal(0.0, distance_sigma)
    hz_noisy = (hz + e_hz) % (2 * np.pi)
    return (0.0 if hz_noisy >= 2 * np.pi else float(hz_noisy)), float(v + e_v), float(d + e_d)


def perturb_points(points: np.ndarray, rng: np.random.Generator, distance_sigma: float = DISTANCE_SIGMA,
                   angle_sigma: float = ANGLE_SIGMA) -> np.ndarray:
    """(N, 3) tracker-frame points as the tracker would read them: each turned into its angles and
    distance, perturbed by `perturb_polar`, and turned back."""
    P = np.atleast_2d(np.asarray(points, dtype=float))
    out = np.empty_like(P)
    for i, xyz in enumerate(P):
        reading = perturb_polar(*cartesian_to_polar(xyz), rng, distance_sigma, angle_sigma)
        out[i] = polar_to_cartesian(*reading)
    return out
