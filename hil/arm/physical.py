"""Link masses and centres of mass, rated payloads and typical joint compliance of the catalog's arms.

A compliant arm sags by compliance × the gravity torque each joint holds
(docs/design.md, "Contracts: non-geometric
errors"); the torque comes from these masses (`hil.arm.gravity`).

**Link masses and centres of mass** are UR's published values as ``ur_description`` carries them:
``config/<robot>/physical_parameters.yaml`` (``inertia_parameters``: ``<link>_mass`` and
``center_of_mass.<link>_cog``) in github.com/UniversalRobots/Universal_Robots_ROS2_Description at
commit 2221ec0f720fb1af99339eb891639b499b62f1da (release 2.4.5). How the numbers are to be read was
checked in the same commit's ``urdf/ur_macro.xacro`` and ``urdf/inc/ur_common.xacro``:

* each link's ``<inertial><origin xyz="${<link>_cog}" rpy="${<link>_inertia_rotation}"/>``: the centre of
  mass is the ``xyz`` in the *link* frame; the ``rpy`` (π/2 pitch for upper arm and forearm, "compatible
  with cylinder approximation") turns only the inertia tensor's axes, never the centre of mass;
* the link frames are the child frames of the six revolute joints, whose origins come from
  ``config/<robot>/default_kinematics.yaml``; for the UR5e those origins equal hil's
  `Geometry.nominal` origins (origin1 = Tz(d1), origin(i+1) = Tx(aᵢ)·Rx(αᵢ)·Tz(dᵢ₊₁)) to 2·10⁻¹⁰ (the
  yaml rounds π/2), and wrist_3 → flange → tool0 is the identity, as hil's flange. So each centre of
  mass below is in hil's joint frame i (after joint i's rotation), which is what `hil.arm.gravity`
  attaches it to;
* the yaml comments (and UR's article "DH Parameters for calculations of kinematics and dynamics",
  universal-robots.com/articles/ur/application-installation/dh-parameters-for-calculations-of-kinematics-
  and-dynamics/) show the conversion from UR's DH-frame values: x − a for the upper arm and forearm,
  (x, −z, y) for shoulder and wrist 1, (x, z, −y) for wrist 2. Spot-checked against that article for the
  UR3e, UR5e, UR10e and UR20: they agree, except the UR20's wrist 3, which the article now gives as
  0.846 kg at z = −0.0318 m (ur_description: 0.926 kg at −0.0293 m); hil keeps ur_description's value,
  as docs/design.md, Facts: compliance says.

The base link (``base_mass``, "might be incorrect") never moves and holds no joint torque; it is left out.

**Rated payloads** are the datasheet payloads at full performance (UR product fact sheets; the UR10e
user manual, "Maximum Payload": "10 kg / 12.5 kg" by label — arms built since 2022 carry 12.5 kg). The
UR20 and UR30 also allow an *expanded* payload (25 kg and 35 kg) only with the tool pointing down (UR30
user manual, "Maximum Payload", "Payload capacity increase"), so the full-performance values are used.

**Typical compliance**: see `typical_compliance` and `gear_compliance`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hil.arm.catalog import get_robot


@dataclass(frozen=True)
class LinkInertia:
    """Mass (kg) of one moving link and its centre of mass (m) in hil's joint frame of that link."""

    mass: float
    com: tuple[float, float, float]


def _links(*rows: tuple[float, float, float, float]) -> tuple[LinkInertia, ...]:
    return tuple(LinkInertia(m, (x, y, z)) for m, x, y, z in rows)


# (mass, cog x, cog y, cog z) for shoulder, upper arm, forearm, wrist 1, wrist 2, wrist 3, copied from
# config/<robot>/physical_parameters.yaml at the commit cited above.
_LINKS: dict[str, tuple[LinkInertia, ...]] = {
    "ur3e": _links((1.98, 0.0, 0.0, -0.02), (3.4445, -0.11355, 0.0, 0.1157), (1.437, -0.1632, 0.0, 0.0238),
                   (0.871, 0.0, -0.01, 0.0), (0.805, 0.0, 0.01, 0.0), (0.261, 0.0, 0.0, -0.02)),
    "ur5e": _links((3.761, 0.0, -0.00193, -0.02561), (8.058, -0.2125, 0.0, 0.11336),
                   (2.846, -0.2422, 0.0, 0.0265), (1.37, 0.0, -0.01634, -0.0018),
                   (1.3, 0.0, 0.01634, -0.0018), (0.365, 0.0, 0.0, -0.001159)),
    "ur10e": _links((7.369, 0.021, -0.027, 0.0), (13.051, -0.2327, 0.0, 0.158),
                    (3.989, -0.33155, 0.0, 0.068), (2.1, 0.0, -0.018, 0.007),
                    (1.98, 0.0, 0.018, -0.007), (0.615, 0.0, 0.0, -0.026)),
    "ur16e": _links((7.369, 0.0, -0.030, -0.016), (10.450, -0.1764, 0.0, 0.16),
                    (4.321, -0.166, 0.0, 0.065), (2.180, 0.0, -0.011, -0.009),
                    (2.033, 0.0, 0.012, -0.018), (0.907, 0.0, 0.0, -0.044)),
    "ur20": _links((16.343, 0.0, -0.0062, -0.061), (29.632, -0.3394, 0.0, 0.2098),
                   (7.879, -0.4053, 0.0, 0.0604), (3.054, 0.0, -0.0393, -0.0026),
                   (3.126, 0.0, 0.0379, -0.0024), (0.926, 0.0, 0.0, -0.0293)),
    "ur30": _links((16.343, -0.0001, -0.0069, -0.06), (28.542, -0.2476, 0.0, 0.2103),
                   (7.156, -0.278, 0.0, 0.0629), (3.054, 0.0, -0.0353, -0.0048),
                   (3.126, 0.0, 0.0341, -0.0046), (0.926, 0.0, 0.0, -0.0293)),
    "ur3": _links((2.0, 0.0, 0.0, -0.02), (3.42, -0.11365, 0.0, 0.1157), (1.26, -0.16325, 0.0, 0.0238),
                  (0.8, 0.0, -0.01, 0.0), (0.8, 0.0, 0.01, 0.0), (0.35, 0.0, 0.0, -0.02)),
    "ur5": _links((3.7, 0.0, -0.00193, -0.02561), (8.393, -0.2125, 0.0, 0.11336),
                  (2.33, -0.24225, 0.0, 0.0265), (1.219, 0.0, -0.01634, -0.0018),
                  (1.219, 0.0, 0.01634, -0.0018), (0.1879, 0.0, 0.0, -0.001159)),
    "ur10": _links((7.1, 0.021, -0.027, 0.0), (12.7, -0.232, 0.0, 0.158), (4.27, -0.3323, 0.0, 0.068),
                   (2.0, 0.0, -0.018, 0.007), (2.0, 0.0, 0.018, -0.007), (0.365, 0.0, 0.0, -0.026)),
}

#: Datasheet payload at full performance (kg); see the module docstring.
_RATED_PAYLOAD: dict[str, float] = {
    "ur3e": 3.0, "ur5e": 5.0, "ur10e": 12.5, "ur16e": 16.0, "ur20": 20.0, "ur30": 30.0,
    "ur3": 3.0, "ur5": 5.0, "ur10": 10.0,
}


def link_inertias(robot: str) -> tuple[LinkInertia, ...]:
    """The six moving links' masses and centres of mass (joint order: shoulder … wrist 3)."""
    return _LINKS[get_robot(robot).name]


def rated_payload(robot: str) -> float:
    """The arm's rated payload (kg), full performance (UR datasheets; see the module docstring)."""
    return _RATED_PAYLOAD[get_robot(robot).name]


#: Torsional stiffness K3 (Nm/rad, above the T2 knee, where it is nearly linear) of Harmonic Drive
#: CSF/CSG cup-type gears of ratio ≥ 80, by size. Size 32 (1.2·10⁵) is the worked example of Harmonic
#: Drive's "Calculation of the Torsion Angle" (CHA series manual 1018854 12/2015 p. 68; LynxDrive
#: manual 1018856 08/2018 p. 42: T1 = 29 Nm, K1 = 6.7·10⁴, T2 = 108 Nm, K2 = 1.1·10⁵, K3 = 1.2·10⁵);
#: the other sizes are the ratio ≥ 80 table of the "CSF & CSG Series" catalog (Harmonic Drive LLC,
#: "Torsional Stiffness", table 43) as recalled, not re-read: the catalog excerpt at hand showed only
#: its ratio-50 table 42 (K1 0.34/0.81/1.3/2.5/5.4·10⁴, K2 0.47/1.1/1.8/3.4/7.8·10⁴ for sizes
#: 14/17/20/25/32), which these exceed as a higher ratio's should. Check them before relying on them.
HARMONIC_DRIVE_K3: dict[int, float] = {
    11: 0.47e4, 14: 0.71e4, 17: 1.6e4, 20: 2.9e4, 25: 5.7e4, 32: 12e4, 40: 23e4,
}

#: Gear size behind each joint torque class (N·m, the catalog's ``effort`` = ur_description's
#: ``max_effort``). UR does not publish its gears; the classes coincide with the repeated peak torque
#: of Harmonic Drive ratio-100 cup gears (CSF-14 28 Nm, CSF-17 54 Nm, CSF-25 157 Nm, CSF-32 333 Nm,
#: CSG-32 433 Nm, CSG-20 108 Nm; CSF & CSG catalog "Rating Table"), which is how the sizes are inferred;
#: 12 Nm is taken as size 11 and 738 Nm (between CSF-40 647 Nm and CSG-40 841 Nm) as size 40.
_GEAR_SIZE: dict[float, int] = {
    12.0: 11, 28.0: 14, 54.0: 17, 56.0: 17, 107.0: 20, 150.0: 25, 330.0: 32, 433.0: 32, 738.0: 40,
}

#: Share of the gear's windup that the reported joint angle does not see (hil's assumption, see
#: `typical_compliance`).
UNSEEN_WINDUP = 0.1


def gear_sizes(robot: str) -> np.ndarray:
    """(6,) Harmonic Drive size inferred behind each joint from its torque class (`_GEAR_SIZE`)."""
    spec = get_robot(robot)
    return np.array([_GEAR_SIZE[float(e)] for e in spec.effort], dtype=int)


def gear_compliance(robot: str) -> np.ndarray:
    """(6,) compliance (rad/Nm) of the strain-wave gear in each joint: 1/K3 of its inferred size."""
    return np.array([1.0 / HARMONIC_DRIVE_K3[int(size)] for size in gear_sizes(robot)])


def typical_compliance(robot: str) -> np.ndarray:
    """(6,) joint compliance (rad/Nm) typical of the arm: `UNSEEN_WINDUP` × `gear_compliance`.

    The whole catalog windup would sag the tool by 2–7 mm at full reach with the rated payload
    (UR5e 2.2 mm, UR10e 4.7 mm, UR20 7.1 mm), an order of magnitude more than the some tenths of a
    millimetre the issue asks the simulator to show. UR joints read their angle on both sides of the
    strain-wave gear (Madsen et al., "Dynamics Parametrization and Calibration of Flexible-Joint
    Collaborative Industrial Robot Manipulators", Math. Probl. Eng. 2020, 8709870 — authors from UR:
    "two angular position measurements per robot joint, one at each side of the strain-wave
    transmission"), so most of the windup is measured; what the reported angle misses (output bearing
    tilt, link and flange bending) is modelled as a tenth of the gear's compliance. That factor is
    hil's assumption, chosen for the issue's order of magnitude: it gives 0.19–0.71 mm at full reach
    with the rated payload over the whole catalog (UR5e 0.22 mm, UR10e 0.47 mm; see the tests).
    Joint 1 gets its value too: it holds a torque when the base is not mounted on a floor.
    """
    return UNSEEN_WINDUP * gear_compliance(robot)
