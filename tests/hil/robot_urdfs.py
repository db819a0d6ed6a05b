"""The URDFs of real arms shipped by the `example-robot-data` package, found through its installed files
(importlib.metadata), for the any-arm tests: never hand-written robots.

`ARMS` names each arm hil is tested on with the link its SMR would sit on (the URDFs of the Panda,
the Kinova and the Z1 end in several links or a gripper joint, so the tip is chosen explicitly).
"""

from __future__ import annotations

from importlib import metadata
from pathlib import Path

_ROBOTS = "cmeel.prefix/share/example-robot-data/robots/"

#: name → (path below the package's robots directory, tip link or None for the only end).
ARMS: dict[str, tuple[str, str | None]] = {
    "panda": ("panda_description/urdf/panda.urdf", "panda_link8"),
    "kinova": ("kinova_description/robots/kinova.urdf", "j2s6s200_end_effector"),
    "z1": ("z1_description/urdf/z1.urdf", "link06"),
    "so100": ("so_arm_description/urdf/so100.urdf", "gripper"),
    "ur5": ("ur_description/urdf/ur5_robot.urdf", "tool0"),
    # the Panda out to its left finger: seven revolute joints and a prismatic one
    "panda_finger": ("panda_description/urdf/panda.urdf", "panda_leftfinger"),
}


def urdf_path(relative: str) -> Path:
    """The installed file `relative` (below example-robot-data's robots directory)."""
    path = Path(str(metadata.distribution("example-robot-data").locate_file(_ROBOTS + relative)))
    if not path.is_file():
        raise FileNotFoundError(f"example-robot-data has no {relative}")
    return path


def arm(name: str) -> tuple[Path, str | None]:
    """(URDF path, tip link) of one of `ARMS`."""
    relative, tip = ARMS[name]
    return urdf_path(relative), tip
