"""The real arms' URDFs the any-arm tests run on, from the `example-robot-data` test dependency
(installed by pip as a cmeel package: its files under ``<site-packages>/cmeel.prefix/share``)."""

from __future__ import annotations

import sysconfig
from dataclasses import dataclass
from pathlib import Path

#: Where `package://example-robot-data/...` resolves: the meshes' package directory for pinocchio.
SHARE = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share"
ROBOTS_DIR = SHARE / "example-robot-data" / "robots"


@dataclass(frozen=True)
class RobotUrdf:
    """One arm: its URDF, and the base and tip links of the serial chain the tests use."""

    name: str
    relative: str
    base: str
    tip: str

    @property
    def path(self) -> Path:
        return ROBOTS_DIR / self.relative


ARMS: dict[str, RobotUrdf] = {a.name: a for a in (
    RobotUrdf("panda", "panda_description/urdf/panda.urdf", "panda_link0", "panda_hand_tcp"),
    RobotUrdf("kinova", "kinova_description/robots/kinova.urdf", "base", "j2s6s200_end_effector"),
    RobotUrdf("z1", "z1_description/urdf/z1.urdf", "world", "gripperStator"),
    RobotUrdf("so100", "so_arm_description/urdf/so100.urdf", "base", "gripper"),
    RobotUrdf("ur5", "ur_description/urdf/ur5_robot.urdf", "world", "tool0"),
)}
