"""Plain, immutable records the store hands out (never live rows or cursors).

Readers get snapshots they can keep across threads and after the store is closed; every record has
``as_dict()`` giving the JSON that ``hil history --json`` / ``hil show --json`` print.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from drivers.robot.model import RobotIdentity

ROLES: tuple[str, ...] = ("bootstrap", "calibration", "validation")

#: What a campaign is: a calibration identifies a model; a verification (``hil verify``, ISO 9283)
#: measures how well the arm reaches targets and has no model of its own.
CALIBRATION, VERIFICATION = "calibration", "verification"
KINDS: tuple[str, ...] = (CALIBRATION, VERIFICATION)

# A campaign in one of these states is over: re-running the same command starts a new one. "failed"
# (a hardware fault, a lost connection past its timeout) is deliberately NOT here: once the fault is
# fixed, re-running the command continues the campaign with its measurements.
FINISHED: frozenset[str] = frozenset({"accepted", "rejected", "aborted"})

# Stopped before the end without being aborted — Ctrl-C, SIGTERM, a closed terminal, quitting the TUI
# mid-run, or a process that died (the store reads a run whose owner is gone as this): resumable.
INTERRUPTED = "interrupted"

# Engine states that are also campaign statuses, those of a run in progress (the final status comes
# from RunFinished). A reader finding one whose run's process is gone says INTERRUPTED.
LIVE_STATES: frozenset[str] = frozenset({"running", "paused", "suspended", "stopping"})


def _plain(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    return value


class _AsDict:
    def as_dict(self) -> dict[str, Any]:
        return _plain(self)  # type: ignore[no-any-return]


@dataclass(frozen=True)
class PlannedPose(_AsDict):
    index: int
    role: str
    target: tuple[float, ...]
    status: str = "planned"  # planned, measured, skipped
    reason: str = ""


@dataclass(frozen=True)
class Measurement(_AsDict):
    """One measured point: averaged joints, averaged SMR position, their spreads."""

    id: int
    campaign: str
    index: int
    role: str
    q: tuple[float, ...]
    p: tuple[float, ...]
    q_spread: tuple[float, ...] | None
    p_spread: tuple[float, ...] | None
    samples: int
    deviation: float | None
    t: float


@dataclass(frozen=True)
class CampaignSummary(_AsDict):
    """One line of ``hil history``."""

    id: str
    created: float
    updated: float
    station: str
    robot: str  # type
    serial: str
    status: str
    planned: int  # calibration + validation poses (bootstrap points not counted)
    measured: int
    skipped: int
    fit_rms: float | None  # of the latest model (m)
    validation_rms: float | None  # after calibration, latest validation (m)
    passed: bool | None
    kind: str = CALIBRATION
    # the bootstrap's poses (they locate the tracker before the campaign's poses are planned, and are
    # fitted with the calibration poses): its stored plan's count and how many were measured. A
    # campaign interrupted during its bootstrap has planned 0 and these > 0.
    bootstrap_planned: int = 0
    bootstrap_measured: int = 0

    @property
    def finished(self) -> bool:
        return self.status in FINISHED


@dataclass(frozen=True)
class ModelRecord(_AsDict):
    id: int
    created: float
    rms: float | None
    doc: dict[str, Any]


@dataclass(frozen=True)
class ValidationRecord(_AsDict):
    id: int
    created: float
    model: int | None
    before: dict[str, Any]
    after: dict[str, Any]
    passed: bool
    details: dict[str, Any] | None


@dataclass(frozen=True)
class CampaignRecord(_AsDict):
    """Everything about one campaign except the raw samples and the full event log."""

    summary: CampaignSummary
    robot: RobotIdentity
    config: dict[str, Any]
    config_hash: str
    plan: dict[str, Any] | None
    detail: str
    result: dict[str, Any] | None
    software: str
    poses: list[PlannedPose] = field(default_factory=list)
    measurements: list[Measurement] = field(default_factory=list)
    models: list[ModelRecord] = field(default_factory=list)
    validations: list[ValidationRecord] = field(default_factory=list)
    event_counts: dict[str, int] = field(default_factory=dict)
    # the controller's own kinematic model the campaign ran with (`ControllerModel`), None if unknown
    controller: dict[str, Any] | None = None

    @property
    def id(self) -> str:
        return self.summary.id

    @property
    def model(self) -> ModelRecord | None:
        """The latest model (a resumed or re-identified campaign may have several)."""
        return self.models[-1] if self.models else None

    @property
    def validation(self) -> ValidationRecord | None:
        return self.validations[-1] if self.validations else None
