"""Messages from the session's worker threads to the UI, as dataclasses.

Textual's `Message.__init__` only calls `__post_init__`, so a dataclass's generated ``__init__``
sets up a message correctly. They are posted with `App.post_message`, which is thread-safe: the
engine's worker thread never waits for the UI to draw.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from textual.message import Message

from hil.campaign.events import Event


@dataclass
class StationChanged(Message):
    """The station's connection state or status readings changed (see `hil.tui.state.StationState`)."""


@dataclass
class EngineEvent(Message):
    """One campaign event, forwarded from the engine's event bus."""

    event: Event


@dataclass
class EarlierPoints(Message):
    """The points a resumed campaign measured before it was interrupted (the store's PointMeasured
    events, latest per pose): the Run screen shows them, and counts them as ``hil calibrate`` does."""

    campaign: str
    points: list[Any] = field(default_factory=list)  # hil.campaign.events.PointMeasured


@dataclass
class RunEnded(Message):
    """The run worker finished; the store already holds the campaign's final status and result."""

    campaign: str
    status: str
    detail: str = ""
    quitting: bool = False


@dataclass
class ResumeQuestion(Message):
    """An unfinished campaign of this station, robot and configuration exists: resume it or not?"""

    campaign: str
    measured: int
    planned: int
    bootstrap: int = 0  # bootstrap points measured (apart from the campaign's poses)


@dataclass
class SelectionDone(Message):
    """The Plan screen's selector run finished (`report`: what `select_poses` of
    `hil.calibration.selection` returns)."""

    report: dict[str, Any]
    points: Any  # (N, 3) SMR positions in the base frame
    tracker: tuple[float, float, float]
    assumed_tracker: bool


@dataclass
class SelectionFailed(Message):
    text: str


@dataclass
class CampaignLoaded(Message):
    """A campaign record read from the store, for the Results screen."""

    record: Any  # hil.store.CampaignRecord
    latest: bool = False  # the store's latest, at start-up: shown on Results, not switched to


@dataclass
class HistoryLoaded(Message):
    rows: list[Any] = field(default_factory=list)  # hil.store.CampaignSummary
    database: str = ""


@dataclass
class Exported(Message):
    """Files written by an export action (or the error that stopped it)."""

    paths: list[str] = field(default_factory=list)
    error: str = ""


@dataclass
class Notice(Message):
    """Something the operator must see: a driver error, a refused action. Never fatal."""

    text: str
    severity: str = "information"  # information, warning, error
