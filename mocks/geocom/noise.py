"""Leica-class measurement errors and the atmosphere's effect on distances.

The error model and its figures (the AT960's MPE ±(15 µm + 6 µm/m) read as 2σ: distance σ = 7.5 µm,
angle σ = 3 µrad on Hz and on V) live in `hil.calibration.tracker_noise`, which offline synthetic
measurements use too: one source of truth. `bench/tracker_bench.py` checks the simulator against them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hil.calibration.tracker_noise import ANGLE_SIGMA, DISTANCE_SIGMA, mpe_m, perturb_polar

__all__ = ["NOISELESS", "NoiseSpec", "atmospheric_ppm", "mpe_m"]


@dataclass(frozen=True)
class NoiseSpec:
    """1-σ errors the instrument adds to every reading."""

    distance_sigma_m: float = DISTANCE_SIGMA
    angle_sigma_rad: float = ANGLE_SIGMA

    def perturb(self, hz: float, v: float, d: float, rng: np.random.Generator) -> tuple[float, float, float]:
        """A noisy (hz, v, d) around the true one (`hil.calibration.tracker_noise.perturb_polar`)."""
        return perturb_polar(hz, v, d, rng, self.distance_sigma_m, self.angle_sigma_rad)


NOISELESS = NoiseSpec(0.0, 0.0)


def atmospheric_ppm(temperature_c: float, pressure_mbar: float) -> float:
    """Leica's dry-air ppm correction (humidity neglected): ≈0 at 12 °C and 1013.25 mbar."""
    return 286.34 - 0.29525 * pressure_mbar / (1.0 + temperature_c / 273.15)
