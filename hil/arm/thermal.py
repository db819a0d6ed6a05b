"""Thermal growth of a simulated arm as it warms up (truth only;
docs/design.md, Contracts: non-geometric errors).

Aluminium links lengthen with temperature, and a UR's joints warm up over the first tens of minutes of
running, so an arm measured cold and used warm is a few hundredths to tenths of a millimetre off. The
simulator scales every joint origin's and the flange's translation by 1 + expansion·ΔT(t), with
ΔT(t) = rise·(1 − exp(−t/time_constant)) (a first-order warm-up, t the time the arm has been moving;
the simulator integrates ΔT from what the arm does, `mocks.heating`); the SMR offset
and the tracker pose do not grow. Models never carry this block: hil handles the drift by warming the
arm up and watching a reference pose, not by predicting temperature.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from hil.errors import InputError
from hil.files.quantities import quantity

#: Linear expansion coefficient of aluminium alloys (1/K): 23.1e-6 for pure Al, 23.6e-6 for 6061-T6
#: (ASM Handbook Vol. 2; MatWeb "Aluminum 6061-T6"); UR's links are cast and extruded aluminium.
ALUMINIUM_EXPANSION = 2.3e-5


@dataclass(frozen=True)
class Thermal:
    """Expansion coefficient (1/K), final temperature rise (K) and warm-up time constant (s)."""

    expansion: float = ALUMINIUM_EXPANSION
    rise: float = 6.0
    time_constant: float = 900.0

    def rise_at(self, t: float) -> float:
        """ΔT (K) after `t` seconds of running."""
        return self.rise * (1.0 - math.exp(-max(t, 0.0) / self.time_constant))

    def scale_at(self, t: float) -> float:
        """The factor every link translation is multiplied by after `t` seconds of running."""
        return self.scale_of(self.rise_at(t))

    def scale_of(self, rise: float) -> float:
        """The factor every link translation is multiplied by at a temperature rise of `rise` K (an arm
        that did not run all the time: the simulator's `mocks.heating`)."""
        return 1.0 + self.expansion * rise

    def to_dict(self) -> dict[str, float]:
        return {"expansion": self.expansion, "rise": self.rise, "time_constant": self.time_constant}

    @classmethod
    def from_dict(cls, data: Any, source: str = "thermal") -> Thermal:
        """Parse the truth's ``thermal`` block; InputError naming the field when wrong."""
        if not isinstance(data, Mapping):
            raise InputError(f"{source}: expected an object with 'expansion', 'rise' and 'time_constant'")
        out = {}
        # the ranges are rows of hil.files.quantities (invar to plastics, a rise a running arm can have,
        # a warm-up between a second and a day)
        for key, name in (("expansion", "thermal expansion"), ("rise", "temperature rise"),
                          ("time_constant", "warm-up time constant")):
            if key not in data:
                raise InputError(f"{source}: missing field '{key}'")
            out[key] = quantity(name).json(data[key], f"{source}.{key}")
        return cls(**out)
