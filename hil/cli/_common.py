"""Small helpers shared by the subcommands: option parsing and human-readable figures."""

from __future__ import annotations

import json
import sys
from typing import Any

import numpy as np

from hil.arm.geometry import parse_triplet


def triplet_or_none(text: str | None, option: str) -> np.ndarray | None:
    """An optional "X,Y,Z" option as a vector (InputError naming the option when malformed)."""
    return None if text is None else parse_triplet(text, option)


def mm(value: float) -> str:
    """Metres shown as millimetres with µm resolution."""
    return f"{value * 1e3:.3f} mm"


def print_json(doc: Any) -> None:
    """One JSON document on stdout."""
    json.dump(doc, sys.stdout, indent=2)
    sys.stdout.write("\n")
