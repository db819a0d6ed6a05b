"""Which robot a station has: every source that names it must agree, the controller's word included.

A campaign, a MOVEB run and the simulated station each hear the robot type from several places: the
configuration's ``robot.type``, ``--robot``, a model or truth file's ``"robot"``, and — once connected —
the controller itself (the dashboard's ``get robot model``, as the driver spells it in
`drivers.robot.model.ControllerInfo.model`: ``UR5e`` for an e-Series arm, ``UR5`` for a CB3, ``UR20``).
Kinematics, joint limits and keep-in checks all follow the robot type, so a disagreement is refused
before anything moves: a UR10e model driving a UR5e would plan every pose with the wrong arm.

This module holds no I/O: the callers (`hil.campaign.runner`, `hil.cli.moveb`, `hil.cli.sim`,
`hil.cli.tui`, `hil.station.simulated`) gather the claims and ask here whether they agree.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from hil.arm.catalog import get_robot
from hil.errors import InputError, UnknownRobotError


class ControllerMismatch(InputError):
    """The connected controller reports another robot than the station's (bad input: the configured
    kinematics would drive another arm); its message names every source."""


@dataclass(frozen=True)
class Claim:
    """One source's word on the robot type, and how to name that source in an error.

    `phrase` is the whole clause for a message, e.g. ``"robot.type is ur10e in station.toml"`` or
    ``"the controller at 127.0.0.2 reports UR5e"``: the sources word it differently, so each says it.
    """

    robot: str
    phrase: str

    @property
    def key(self) -> str:
        """The catalog name, or the raw spelling (lower case) for a robot hil does not know."""
        try:
            return get_robot(self.robot).name
        except UnknownRobotError:
            return str(self.robot).strip().lower()


def agreed_robot(claims: Sequence[Claim], default: str | None = None) -> str:
    """The catalog name every claim names (or `default` when there are none).

    Raises InputError naming each source when they disagree ("A and B but C"; those that agree with
    the first source come first): no source overrides another silently, because each of them was
    somebody's deliberate statement about the arm.
    """
    if not claims:
        if default is None:
            raise ValueError("agreed_robot: no claim and no default")
        return get_robot(default).name
    if len({c.key for c in claims}) > 1:
        same = [c.phrase for c in claims if c.key == claims[0].key]
        other = [c.phrase for c in claims if c.key != claims[0].key]
        raise InputError(f"{_listed(same)} but {_listed(other)}")
    return get_robot(claims[0].robot).name  # every claim names this known robot (or an unknown one)


def _listed(phrases: list[str]) -> str:
    """'A', 'A and B', 'A, B and C'."""
    return phrases[0] if len(phrases) == 1 else ", ".join(phrases[:-1]) + f" and {phrases[-1]}"


def option_claim(value: str | None, option: str = "--robot") -> list[Claim]:
    """``--robot`` as a claim (none when not given); an unknown or empty name is refused naming the option."""
    if value is None:
        return []
    try:
        get_robot(value)
    except UnknownRobotError as exc:
        raise InputError(f"{option}: {exc}") from None
    return [Claim(value, f"{option} is {value}")]


def config_claim(config: Any) -> Claim:
    """The station configuration's ``robot.type``, named with its file (not for the built-in defaults)."""
    source = str(getattr(config, "source", "") or "")
    where = f" in {source}" if source and not source.startswith("<") else ""
    return Claim(config.robot["type"], f"robot.type is {config.robot['type']}{where}")


def controller_claim(info: Any, host: str) -> Claim | None:
    """What the connected controller says it is; None when the robot reports no model (a stand-in)."""
    model = getattr(info, "model", None) if info is not None else None
    if not isinstance(model, str):
        return None
    return Claim(model or "(nothing)", f"the controller at {host} reports {model or 'no model'}")


def check_controller(config: Any, info: Any, *others: Claim) -> None:
    """Refuse (InputError, naming each source) a controller whose model is not the configured robot's.

    Called after connect and before any motion; `others` are further sources already checked against
    the configuration (a model file, ``--robot``), named too so the operator sees the whole picture.
    """
    said = controller_claim(info, config.robot["address"])
    if said is None:
        return
    try:
        agreed_robot([config_claim(config), *others, said])
    except InputError as exc:
        raise ControllerMismatch(str(exc)) from None
