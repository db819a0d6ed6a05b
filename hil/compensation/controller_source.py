"""Where the controller's own model comes from: a file holding its ``controller`` block, or the arm.

Compensation needs the deltas the controller adds to its nominal DH
(docs/design.md, "Contracts: the controller's own
calibration"). They are either written down — a simulator truth, a model that carries them, or any
``{"robot": ..., "controller": {...}}`` file — or read from the live controller's KinematicsInfo
package on its primary interface (port 30001), which publishes the full DH table it moves by.
"""

from __future__ import annotations

import os
from typing import Any

from drivers.robot.errors import RobotError
from hil.arm.controller_model import ControllerCalibration
from hil.errors import FaultError, InputError

#: The UR primary client interface, which streams robot-state messages (KinematicsInfo among them).
PRIMARY_PORT = 30001


def _block(doc: dict[str, Any]) -> tuple[Any, Any, str]:
    """(controller block, robot, where the block sits) of a document; a campaign result carries both
    inside its model."""
    if "controller" not in doc and isinstance(doc.get("model"), dict) and "controller" in doc["model"]:
        model = doc["model"]
        return model["controller"], model.get("robot", doc.get("robot")), "model.controller"
    return doc.get("controller"), doc.get("robot"), "controller"


def controller_from_file(path: str | os.PathLike[str], robot: str) -> ControllerCalibration:
    """The ``controller`` block of a JSON file, checked against the model's `robot`."""
    from hil.calibration.model_file import read_json

    doc = read_json(path)
    block, said, where = _block(doc)
    if block is None:
        raise InputError(f"{path}: missing field 'controller' (the controller's calibration: delta_theta, "
                         "delta_a, delta_d, delta_alpha)")
    if said is not None and said != robot:
        raise InputError(f"{path}: robot: the controller's calibration is of a {said!r}, the model of a "
                         f"{robot!r}")
    return ControllerCalibration.from_dict(block, source=f"{path}: {where}")


def controller_from_arm(address: str, robot: str, timeout: float,
                        port: int = PRIMARY_PORT) -> ControllerCalibration:
    """The calibration the controller at `address` moves by (its KinematicsInfo package).

    Not answering, or not sending the package within `timeout` seconds, is a station fault
    (`FaultError`, exit 3) naming the address.
    """
    from drivers.robot.kinematics_info import read_kinematics_info

    try:
        info = read_kinematics_info(address, port=port, timeout=timeout)
    except (OSError, RobotError) as exc:
        said = str(exc) if address in str(exc) else f"{address}:{port}: {type(exc).__name__}: {exc}"
        raise FaultError(f"cannot read the controller's calibration (KinematicsInfo): {said}") from None
    # not held to a file's plausibility limits: the table is the controller's own word (a real one
    # carries cancelling d values on the parallel joints, see `drivers.robot.kinematics_info`)
    return ControllerCalibration.from_dh(robot, *info.dh())
