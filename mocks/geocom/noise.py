"""Leica-class measurement errors and the atmosphere's effect on distances.

Spec: MPE ≈ ±(15 µm + 6 µm/m · d), typical about half of it. We read MPE as ≈2σ per component
and split it into a radial and a transverse part: distance σ = 7.5 µm, angle σ = 3 µrad on Hz and
on V (3 µm/m transverse). `bench/tracker_bench.py` checks the simulator against these numbers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def mpe_m(distance_m: float, constant_m: float = 15e-6, proportional: float = 6e-6) -> float:
    """Maximum permissible error of a point at ``distance_m`` (metres)."""
    return constant_m + proportional * distance_m


@dataclass(frozen=True)
class NoiseSpec:
    """1-σ errors the instrument adds to every reading."""

    distance_sigma_m: float = 7.5e-6
    angle_sigma_rad: float = 3.0e-6

    def perturb(self, hz: float, v: float, d: float, rng: np.random.Generator) -> tuple[float, float, float]:
        """A noisy (hz, v, d) around the true one."""
        e_hz, e_v = rng.normal(0.0, self.angle_sigma_rad, 2)
        e_d = rng.normal(0.0, self.distance_sigma_m)
        hz_noisy = (hz + e_hz) % (2 * np.pi)
        return (0.0 if hz_noisy >= 2 * np.pi else hz_noisy), v + e_v, d + e_d


NOISELESS = NoiseSpec(0.0, 0.0)


def atmospheric_ppm(temperature_c: float, pressure_mbar: float) -> float:
    """Leica's dry-air ppm correction (humidity neglected): ≈0 at 12 °C and 1013.25 mbar."""
    return 286.34 - 0.29525 * pressure_mbar / (1.0 + temperature_c / 273.15)
