"""What a verification is given, read and checked before the station is taken: hil's model
(`load_model`, `ModelInput`) and the ISO 9283 test cube of the configuration (`requested_cube`).

Apart from `hil.verify.session` (the run, which imports the campaign runner: most of a second cold),
so that ``hil verify`` refuses a bad model, a missing cube or — once connected — a controller of
another robot without loading the runner first (issue 31: every refusal within 2 s).
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from hil.errors import InputError
from hil.store.hashing import canonical_json
from hil.verify.cube import Cube

if TYPE_CHECKING:
    from hil.arm.geometry import Geometry
    from hil.station.config import StationConfig

#: The geometry block of a model document: what its sha256 (the verification's identity) covers.
MODEL_KEYS = ("robot", "joints", "flange", "smr", "tracker", "compliance", "payload")


@dataclass(frozen=True)
class ModelInput:
    """hil's calibrated model for the compensated mode, and where it came from."""

    geometry: Geometry
    sha256: str
    source: str  # a file, or "campaign <id>"

    @classmethod
    def of(cls, doc: Mapping[str, Any], geometry: Geometry, source: str) -> ModelInput:
        block = {k: doc[k] for k in MODEL_KEYS if k in doc}
        return cls(geometry, hashlib.sha256(canonical_json(block).encode()).hexdigest(), source)

    def as_dict(self) -> dict[str, Any]:
        return {"source": self.source, "sha256": self.sha256}


def load_model(path: str) -> ModelInput:
    """A model file (``hil-model/1``, or a ``hil calibrate --out`` result embedding one); InputError
    naming the file when it is missing or wrong."""
    from hil.calibration.model_file import MODEL_FORMAT, load_geometry

    geometry, doc = load_geometry(path, (MODEL_FORMAT,))
    return ModelInput.of(doc, geometry, str(path))


def requested_cube(config: StationConfig, sim: bool) -> Cube | None:
    """The ``[verify]`` cube, or None for the default one (``--sim`` only: `default_cube`).

    A real station must name its cube: ISO 9283 puts it in the part of the working space the cell uses
    most, which hil cannot guess, and a cube guessed wrong is one the arm is driven around in.
    """
    v = config.verify
    if v["centre"] is None:
        if sim:
            return None
        raise InputError(f"{config.source}: verify.centre: the ISO 9283 test cube's centre (robot base "
                         "frame, m) is required on a station, e.g. centre = [0.5, 0.0, 0.3]")
    from hil.arm.catalog import get_robot

    edge = v["edge"] if v["edge"] is not None else round(0.25 * get_robot(config.robot["type"]).reach, 3)
    return Cube(np.array(v["centre"]), edge)


def cube_where(config: StationConfig) -> str:
    """How an error names the cube: the configuration's keys, or the simulated station's default."""
    if config.verify["centre"] is None:
        return "the default test cube"
    return f"{config.source}: verify.centre/verify.edge" if not config.source.startswith("<") else \
        "verify.centre/verify.edge"
