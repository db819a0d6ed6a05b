"""Angle-dependent joint errors and lost motion: what separates a joint's link from its encoder.

A real arm's link angle is not its encoder reading plus a constant: an encoder mounted slightly off its
axis reads a once-per-turn error, a strain-wave gear adds its transmission error at low harmonics of the
output angle (and at twice the wave generator's frequency, far beyond what a few poses can resolve), and
the link lags the encoder by a small angle in the direction of the joint's last motion (lost motion:
backlash, the gear's hysteresis). docs/design.md (Contracts: non-geometric errors) fixes the model and
its JSON:

    "joint_errors": [[[k, a, b], ...], ...6 joints]   link angle += Σ a·cos(k·q) + b·sin(k·q)   (rad)
    "lost_motion": [h1, ..., h6]                       link lags the encoder by h·sign(last motion)

applied after compliance: q_link = q_enc − c ⊙ τ(q) + e(q) − h ⊙ sign(Δq_last). Each term is evaluated at
the encoder angle q (what the controller reports), so a model predicts from what it is given.

This module holds the block's value type, its file form and its evaluation; `Kinematics.link_angles`
applies it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hil.errors import InputError
from hil.files.quantities import quantity

#: Largest amplitude (rad) a file may give one harmonic: a hundred times what published UR-class joints
#: show (tens of microradians, see `hil.calibration.synthetic`); beyond it a file is in degrees or broken.
MAX_AMPLITUDE = quantity("harmonic amplitude").high
#: Largest harmonic order a file may give: a strain-wave gear's transmission error runs at twice the wave
#: generator's speed, i.e. 2·ratio per output turn; UR's ratios are 100–160 (the Harmonic Drive catalog's
#: ratios 50–160), so 2·160 = 320, with room to spare.
MAX_ORDER = 1000
#: Largest lost motion (rad) a file may give: a hundred times a strain-wave gear's (Harmonic Drive
#: CSF catalog, "Hysteresis loss": about 1 arc-min = 2.9e-4 rad at ratio ≥ 80 is the catalog's
#: largest figure) — a file beyond it is in degrees or broken.
MAX_LOST_MOTION = quantity("lost motion").high


@dataclass(frozen=True)
class Harmonic:
    """One term of a joint's error: a·cos(k·q) + b·sin(k·q) rad."""

    order: int
    cos: float
    sin: float


@dataclass(frozen=True)
class JointErrors:
    """Each joint's angle-dependent error as a sum of harmonics of its encoder angle."""

    joints: tuple[tuple[Harmonic, ...], ...]

    def __post_init__(self) -> None:
        if len(self.joints) != 6:
            raise InputError(f"joint_errors: expected 6 joints, got {len(self.joints)}")

    @classmethod
    def of(cls, terms: Sequence[Sequence[Sequence[float]]]) -> JointErrors:
        """From the file form: per joint a list of ``[k, a, b]``."""
        return cls(tuple(tuple(Harmonic(int(k), float(a), float(b)) for k, a, b in joint)
                         for joint in terms))

    @property
    def empty(self) -> bool:
        return not any(self.joints)

    def offsets(self, Q: np.ndarray) -> np.ndarray:
        """(N, 6) link-angle errors e(q) at encoder angles `Q` (N, 6)."""
        Q = np.asarray(Q, dtype=float)
        out = np.zeros_like(Q)
        for j, terms in enumerate(self.joints):
            for h in terms:
                out[:, j] += h.cos * np.cos(h.order * Q[:, j]) + h.sin * np.sin(h.order * Q[:, j])
        return out

    def slopes(self, Q: np.ndarray) -> np.ndarray:
        """(N, 6) de/dq at `Q`: how fast the error turns with the joint (IK's fixed point needs it < 1)."""
        Q = np.asarray(Q, dtype=float)
        out = np.zeros_like(Q)
        for j, terms in enumerate(self.joints):
            for h in terms:
                k = h.order
                out[:, j] += k * (h.sin * np.cos(k * Q[:, j]) - h.cos * np.sin(k * Q[:, j]))
        return out

    def up_to(self, order: int) -> JointErrors:
        """The terms of order ≤ `order` only (the part a low-order model can capture)."""
        return JointErrors(tuple(tuple(h for h in terms if h.order <= order) for terms in self.joints))

    def to_list(self) -> list[list[list[float]]]:
        return [[[h.order, h.cos, h.sin] for h in terms] for terms in self.joints]

    @classmethod
    def from_value(cls, value: Any, source: str) -> JointErrors:
        """Parse the ``joint_errors`` block; InputError naming the joint and term otherwise."""
        if not isinstance(value, list) or len(value) != 6:
            raise InputError(f"{source}: field 'joint_errors' must be a list of 6 joints' term lists")
        joints: list[tuple[Harmonic, ...]] = []
        for j, terms in enumerate(value):
            where = f"{source}: field 'joint_errors[{j}]'"
            if not isinstance(terms, list):
                raise InputError(f"{where} must be a list of [k, a, b] terms")
            parsed: list[Harmonic] = []
            for t, term in enumerate(terms):
                parsed.append(_harmonic(term, f"{where}[{t}]"))
            orders = [h.order for h in parsed]
            if len(set(orders)) != len(orders):
                raise InputError(f"{where} gives one harmonic order twice")
            joints.append(tuple(parsed))
        return cls(tuple(joints))


def _harmonic(term: Any, where: str) -> Harmonic:
    if not isinstance(term, list | tuple) or len(term) != 3:
        raise InputError(f"{where} must be [k, a, b]")
    k, a, b = term
    whole = (not isinstance(k, bool) and isinstance(k, int | float) and bool(np.isfinite(k))
             and float(k) == int(k))
    if not whole or not 1 <= k <= MAX_ORDER:
        raise InputError(f"{where}: the order k must be a whole number from 1 to {MAX_ORDER}, got {k!r}")
    row = quantity("harmonic amplitude")  # ±MAX_AMPLITUDE, the table's row
    return Harmonic(int(k), row.json(a, f"{where}: a"), row.json(b, f"{where}: b"))


def parse_lost_motion(value: Any, source: str) -> np.ndarray:
    """Parse the ``lost_motion`` block: 6 angles (rad), each within ±`MAX_LOST_MOTION`."""
    if not isinstance(value, list | tuple) or len(value) != 6:
        raise InputError(f"{source}: field 'lost_motion' must be a list of 6 angles (rad)")
    row = quantity("lost motion")  # ±MAX_LOST_MOTION, the table's row
    return np.array([row.json(v, f"{source}: field 'lost_motion'[{j}]") for j, v in enumerate(value)])


def motion_directions(q_from: np.ndarray, q_to: np.ndarray, previous: np.ndarray | None = None,
                      threshold: float = 0.0) -> np.ndarray:
    """sign(Δq) per joint for a move from `q_from` to `q_to`; a joint that did not move (|Δq| ≤
    `threshold`) keeps its `previous` direction (0 when none): lost motion remembers the last motion."""
    d = np.asarray(q_to, dtype=float) - np.asarray(q_from, dtype=float)
    out = np.sign(d) * (np.abs(d) > threshold)
    if previous is not None:
        out = np.where(out == 0, np.asarray(previous, dtype=float), out)
    return out


def block_of(data: Mapping[str, Any], source: str) -> tuple[JointErrors | None, np.ndarray | None]:
    """The ``joint_errors`` and ``lost_motion`` blocks of a geometry document (None where absent)."""
    errors = (JointErrors.from_value(data["joint_errors"], source)
              if data.get("joint_errors") is not None else None)
    lost = (parse_lost_motion(data["lost_motion"], source)
            if data.get("lost_motion") is not None else None)
    return errors, lost
