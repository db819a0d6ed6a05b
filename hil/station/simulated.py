"""The simulated station as a context: start the simulators, yield the configuration to run with.

Shared by ``hil calibrate --sim``, ``hil moveb run --sim`` and ``hil tui --sim``. The simulator's
address is random, so a run is identified in the store by what it simulates (robot, seed, truth
file's hash) rather than by where it listens: re-running the same command resumes the same campaign.

The configuration says what an operator of that arm would know: the payload on its flange
(``robot.payload``, the truth's), how its base is mounted (``robot.mounting``, from the truth's
gravity) and where the SMR sits on the flange (``smr.offset``, from the SMR holder's drawing:
`operator_knowledge`); never the truth's compliance or warm-up, which are what hil has to find out or
cope with.
"""

from __future__ import annotations

import contextlib
import hashlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from hil.arm.catalog import get_robot
from hil.station.config import SIMULATED_IDENTITY, StationConfig, default_config
from hil.station.robot_type import Claim, agreed_robot


@contextlib.contextmanager
def simulated_station(robot: str | None = None, truth: str | None = None, speed: float = 1.0, seed: int = 1,
                      tracker_protocol: str = "geocom", *, rigid: bool = False, ideal: bool | None = None,
                      **overrides: Any) -> Iterator[tuple[StationConfig, dict[str, Any], dict, Any]]:
    """(config to run, config identifying the run, hidden truth document, running simulator).

    The simulated tracker speaks both protocols at once (GeoCOM on a pty and TCP, emScon TPI on TCP);
    `tracker_protocol` chooses which one the run talks to.

    The robot is `robot`, else the truth's, else a UR5e; a `robot` the truth disagrees with is refused
    (InputError naming both) rather than silently replaced, so the simulated controller always reports
    the arm the caller asked for and the truth describes. `rigid` (without `truth`): a random arm
    without compliance, payload and warm-up; `ideal` (without `truth`; None: the simulator's default,
    `hil.calibration.synthetic.IDEAL_BY_DEFAULT`): without joint errors and lost motion.
    """
    truth_sha = ""
    if truth:
        from hil.calibration.model_file import load_truth

        geometry, _ = load_truth(truth)  # a bad truth fails here, naming the key
        claims = [Claim(robot, f"--robot is {robot}")] if robot is not None else []
        robot = agreed_robot([*claims, Claim(geometry.robot, f"the truth {truth} is for {geometry.robot}")])
        truth = str(Path(truth).resolve())  # the simulator runs in a process of its own, elsewhere
        truth_sha = hashlib.sha256(Path(truth).read_bytes()).hexdigest()
    robot = get_robot("ur5e" if robot is None else robot).name
    from hil.arm.joint_physics import IDEAL_BY_DEFAULT
    from mocks.station import start_station

    sim = start_station(robot=robot, truth=truth, speed=speed, seed=seed, rigid=rigid,
                        ideal=IDEAL_BY_DEFAULT if ideal is None else ideal)
    try:
        station = sim.info["services"][0]
        known = {**operator_knowledge(station["truth"]), **overrides}
        base = default_config().with_overrides(
            station__name="simulated station", robot__type=robot, robot__speed=1.0,
            robot__acceleration=2.0, campaign__seed=seed, tracker__protocol=tracker_protocol, **known)
        url = station["tracker_emscon_url"] if tracker_protocol == "emscon" else station["tracker_url"]
        config = base.with_overrides(robot__address=sim.address, tracker__url=url)
        identity = base.with_overrides(robot__address="sim",
                                       tracker__url=f"{SIMULATED_IDENTITY}seed={seed};truth={truth_sha}").as_dict()
        yield config, identity, station["truth"], sim
    finally:
        sim.stop()


#: How well an operator knows where the SMR centre sits on the flange (m): from the SMR holder's
#: drawing, a machined plate dowelled to the ISO 9409-1 flange, whose un-toleranced dimensions hold
#: ISO 2768-1 class m (±0.2 mm over 6-30 mm, ±0.3 mm over 30-120 mm). The simulated operator reads the
#: truth's offset off such a drawing, to the nearest 0.5 mm: at most 0.25 mm an axis.
SMR_DRAWING_STEP = 0.5e-3


def operator_knowledge(truth: dict[str, Any]) -> dict[str, Any]:
    """Config overrides for what the simulated arm's operator knows: its payload, its mounting and
    where its SMR sits (`SMR_DRAWING_STEP`). The SMR offset matters most to a run without a model
    (``hil moveb run``), which must assume it: an offset wrong by e mm shows as path error of about
    e·sin(θ) where the tool turns by θ, which no rigid fit removes.

    The mounting is the roll and pitch that turn floor gravity into the truth's (yaw does not change
    gravity): with u = −g/|g| the base's world z axis seen in the base frame, u = (−sin p, cos p sin r,
    cos p cos r) for R = Ry(p)·Rx(r).
    """
    out: dict[str, Any] = {}
    if truth.get("smr") is not None:
        drawing = np.round(np.asarray(truth["smr"], dtype=float) / SMR_DRAWING_STEP) * SMR_DRAWING_STEP
        out["smr__offset"] = [float(v) for v in drawing]
    if truth.get("payload") is not None:
        out["robot__payload"] = truth["payload"]
    gravity = truth.get("gravity")
    if gravity is not None:
        u = -np.asarray(gravity, dtype=float) / np.linalg.norm(gravity)
        pitch = float(np.arcsin(np.clip(-u[0], -1.0, 1.0)))
        roll = float(np.arctan2(u[1], u[2]))
        out["robot__mounting"] = [roll, pitch, 0.0]
    return out
