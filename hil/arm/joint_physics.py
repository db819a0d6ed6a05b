"""What separates a UR joint's reported angle from its link's, by published figures: the typical
angle-dependent joint errors and lost motion a simulated truth draws (`hil.arm.joint_errors` holds
the model, docs/design.md, Contracts: non-geometric errors, its JSON).

**What is left to see.** A UR joint reads its angle on both sides of its strain-wave gear (Madsen et
al., Math. Probl. Eng. 2020, 8709870, authors from UR: "two angular position measurements per robot
joint, one at each side of the strain-wave transmission"; `hil.arm.physical`), so the reported angle is
the output encoder's. The gear's own transmission error — 1 to 2 arc-min peak to peak over one output
turn for Harmonic Drive CSF/CSG gears of ratio ≥ 50 (Harmonic Drive LLC, "CSF & CSG Series" catalog,
"Positioning Accuracy", table 40: 2.9·10⁻⁴ rad for sizes 20–32, 4.4·10⁻⁴ for 17–25 and 5.8·10⁻⁴ for
size 14, standard grade), mostly at twice the wave generator's speed (Tuttle, "Understanding and
Modeling the Behavior of a Harmonic Drive Gear Transmission", MIT AI-TR 1365, 1992: the kinematic
error runs at wave-generator harmonics) — is inside the loop and does not reach the link. What
remains is the output encoder's own error against the joint's true axis:

* **Eccentricity** (once per turn). An encoder graduation (or magnetic ring) off the bearing's axis
  by e µm reads an error of ±412·e/D arc-seconds at mean graduation diameter D mm; half of the
  bearing's radial runout counts as eccentricity too (HEIDENHAIN, "Position Encoders for Servo Drives"
  catalogue, "Measuring accuracy": Δφ = ±412·e/D; the same relation in Numerik Jena's RIK manual,
  §6.3). UR does not publish its rings; the ring is taken at the gear's pitch circle, which a Harmonic
  Drive size number gives in tenths of an inch (size 20 ≈ 2.0 in ≈ 51 mm; the gear size behind each
  joint is `hil.arm.physical.gear_sizes`). e: `ECCENTRICITY_SIGMA` per axis (see there).
* **Second harmonic** (twice per turn): a ring's out-of-roundness and tilt, and a magnetic encoder's
  second-order field error; a joint module's angle error is modelled and compensated by its first
  harmonics (Hu et al., "An Angle Error Compensation Method Based on Harmonic Analysis for Integrated
  Joint Modules", Sensors 2020, 20(6), 1715, a harmonic-drive joint module read by a magnetic encoder
  on the output). Its size relative to the first is `SECOND_HARMONIC_RATIO` (an assumption, see there).
* **The part no low-order model captures**: the encoder's position error within one signal period,
  repeated every period, so at the ring's period count per turn. HEIDENHAIN's catalogue (ibid.,
  "Position error within one signal period") gives ±13″ for 1 024 periods and ±25″ for 512 (1 V_PP
  signals, "already included in the system accuracy"); `INTERPOLATION_ERROR` draws one of those
  counts per joint and an amplitude up to its figure.

**Lost motion.** The gear's hysteresis loss (the catalog's "Hysteresis Loss": 1 arc-min, 2.9·10⁻⁴ rad,
for ratio ≥ 80) is measured by the output encoder like the gear's windup; what the reported angle
misses is the output side's own play, modelled as the same share of the gear's figure that
`hil.arm.physical.UNSEEN_WINDUP` takes of its compliance (hil's assumption, for the same reason).

**Repeatability** (`standstill_sigma`). A joint's servo brings its output encoder to the commanded
angle only to within a small error that differs from stop to stop (the encoder's resolution, the
gear's friction and lost-motion band the position loop settles in, the controller's error at
standstill). UR does not publish the joint-level figure, only the arm's: pose repeatability per
ISO 9283, ±0.03 mm for the UR3e and UR5e, ±0.05 mm for the UR10e, UR16e and UR20, ±0.1 mm for the
UR30 and the CB3 UR3, UR5 and UR10 (Universal Robots, e-Series and CB3 technical specifications,
"Pose repeatability per ISO 9283"). The simulated arm's stops scatter by one σ per joint such that
its own RP (without any instrument's noise) is that figure: ISO 9283's RP = l̄ + 3·S_l is
`RP_PER_SIGMA` σ for an isotropic Gaussian scatter of σ per axis, and the SMR moves
`lever_per_axis` metres per axis per radian of joint scatter (RMS over the workspace). That the arm
meets its datasheet figure, no better, is hil's assumption: no published measurement of a UR's
repeatability by an instrument finer than the figure itself was found (a laser tracker's own noise
is of the same size: Slamani, Nubiola & Bonev, Industrial Robot 39(1), 2012). The encoders see this
error (the reading is the output side's), so it scatters commanded poses (ISO 9283's RP, a drift
watch's reference) but not a calibration's measured joints.

With these, a geometry-only fit of a simulated UR5e or UR10e predicts held-out poses at about a tenth
to a quarter of a millimetre, as real UR arms do (docs/design.md, Facts: what real arms reach;
`bench/realistic_arm.py` measures it).
"""

from __future__ import annotations

from functools import cache

import numpy as np

from hil.arm.catalog import get_robot
from hil.arm.joint_errors import Harmonic, JointErrors
from hil.arm.physical import UNSEEN_WINDUP, gear_sizes

#: Whether a simulated arm is the ideal one unless asked otherwise (`hil.calibration.synthetic.random_truth`'s
#: `ideal`, the simulated station's, ``--ideal``/``--no-ideal``): the ideal arm is hil's arm before
#: the ideal arm (geometry, compliance, payload, warm-up), the other the realistic one with these joint
#: errors and lost motion.
IDEAL_BY_DEFAULT = False

#: Radians per arc-second.
ARCSEC = np.pi / (180 * 3600)
#: HEIDENHAIN's eccentricity relation: error (arc-seconds) = ±412 · e (µm) / D (mm).
ECCENTRICITY_ARCSEC = 412.0
#: Millimetres of pitch-circle diameter per Harmonic Drive size number (the size is the circular
#: spline's pitch diameter in tenths of an inch).
MM_PER_GEAR_SIZE = 2.54
#: Standard deviation (µm, per radial axis) of the output encoder's eccentricity to the joint's axis:
#: half the radial runout of the output bearing's inner ring (ISO 492 normal tolerance class, 50–120 mm
#: bore: 15–20 µm, so 7.5–10 µm) is the larger part, the ring's seat on its hub (a few µm) the smaller;
#: 5 µm per axis gives a typical |e| of 6 µm. UR does not publish it: this is hil's assumption from
#: those tolerances, and it sets the simulated arm's accuracy floor (see the module docstring).
ECCENTRICITY_SIGMA = 5.0
#: The second harmonic's standard deviation as a share of the first's (hil's assumption: a ring's
#: out-of-roundness and tilt are second-order effects of its mounting, smaller than its eccentricity).
SECOND_HARMONIC_RATIO = 0.5
#: (signal periods per turn, HEIDENHAIN's largest position error within one period in arc-seconds, 1 V_PP).
INTERPOLATION_ERROR: tuple[tuple[int, float], ...] = ((512, 25.0), (1000, 14.0))
#: Harmonic Drive CSF/CSG "Hysteresis Loss" (rad) for ratio ≥ 80: 1 arc-min.
GEAR_HYSTERESIS = 60 * ARCSEC


def graduation_diameters(robot: str) -> np.ndarray:
    """(6,) mean graduation diameter (mm) of each joint's output encoder, taken at its gear's pitch
    circle (see the module docstring)."""
    return MM_PER_GEAR_SIZE * gear_sizes(robot).astype(float)


def eccentricity_amplitudes(robot: str, eccentricity_um: float = ECCENTRICITY_SIGMA) -> np.ndarray:
    """(6,) once-per-turn error (rad) of each joint's output encoder at eccentricity `eccentricity_um`."""
    return ECCENTRICITY_ARCSEC * eccentricity_um / graduation_diameters(robot) * ARCSEC


def typical_joint_errors(robot: str, rng: np.random.Generator) -> JointErrors:
    """One arm's joint errors, drawn: per joint an eccentricity (k = 1), a second harmonic (k = 2) and
    an interpolation error at its encoder's period count (see the module docstring)."""
    first = eccentricity_amplitudes(robot)
    joints: list[tuple[Harmonic, ...]] = []
    for j in range(6):
        a1, b1 = rng.normal(0.0, first[j], 2)
        a2, b2 = rng.normal(0.0, SECOND_HARMONIC_RATIO * first[j], 2)
        periods, worst = INTERPOLATION_ERROR[int(rng.integers(len(INTERPOLATION_ERROR)))]
        amplitude = rng.uniform(0.0, worst) * ARCSEC
        phase = rng.uniform(-np.pi, np.pi)
        joints.append((Harmonic(1, float(a1), float(b1)), Harmonic(2, float(a2), float(b2)),
                       Harmonic(periods, float(amplitude * np.cos(phase)), float(amplitude * np.sin(phase)))))
    return JointErrors(tuple(joints))


def typical_lost_motion(robot: str, rng: np.random.Generator) -> np.ndarray:
    """(6,) lost motion (rad) of one arm, drawn: `UNSEEN_WINDUP` of the gear's hysteresis loss, each
    joint 0.5–1.5 times it (a catalog figure is a typical value; joints of one size differ)."""
    gear_sizes(robot)  # a robot the catalog knows
    return UNSEEN_WINDUP * GEAR_HYSTERESIS * rng.uniform(0.5, 1.5, 6)


#: Pose repeatability per ISO 9283 (m, RP: the datasheet's "±" figure), Universal Robots' technical
#: specifications of each model (e-Series: UR3e/UR5e ±0.03 mm, UR10e/UR16e/UR20 ±0.05 mm, UR30 ±0.1 mm;
#: CB3: UR3/UR5/UR10 ±0.1 mm).
POSE_REPEATABILITY: dict[str, float] = {
    "ur3e": 0.03e-3, "ur5e": 0.03e-3, "ur10e": 0.05e-3, "ur16e": 0.05e-3, "ur20": 0.05e-3,
    "ur30": 0.1e-3, "ur3": 0.1e-3, "ur5": 0.1e-3, "ur10": 0.1e-3,
}
#: ISO 9283's RP = l̄ + 3·S_l in units of σ for an isotropic Gaussian scatter of σ per axis: the
#: distance l from the barycentre is Maxwell-distributed, mean 2σ·√(2/π), standard deviation
#: σ·√(3 − 8/π).
RP_PER_SIGMA = 2.0 * np.sqrt(2.0 / np.pi) + 3.0 * np.sqrt(3.0 - 8.0 / np.pi)
#: Workspace poses (seeded, so the figure is the same on every run) over which `lever_per_axis`
#: averages, and the SMR's offset on the flange they are taken with (a flange-mounted nest).
LEVER_POSES, LEVER_SEED, LEVER_SMR = 200, 30, (0.0, 0.0, 0.045)


@cache
def lever_per_axis(robot: str) -> float:
    """RMS over workspace poses (upper arm above the shoulder, any other angle) of how far the SMR
    moves per axis (m) for one radian of independent scatter on every joint: √(trace(J·Jᵀ)/3)."""
    from hil.arm.geometry import Geometry  # pinocchio: loaded by the one caller that needs it, not by
    from hil.arm.kinematics import Kinematics  # every help text that names the ideal arm's default

    spec = get_robot(robot)
    rng = np.random.default_rng(LEVER_SEED)
    q = rng.uniform(-np.pi, np.pi, (LEVER_POSES, 6))
    q[:, 1] = rng.uniform(-np.pi, 0.0, LEVER_POSES)
    J = Kinematics(Geometry.nominal(spec, smr=LEVER_SMR)).joint_sensitivities(q)
    return float(np.sqrt(np.mean(np.einsum("nij,nij->n", J, J)) / 3.0))


def standstill_sigma(robot: str) -> float:
    """σ (rad) of each joint's stop-to-stop position error, so that the arm's own ISO 9283 RP is its
    datasheet figure (`POSE_REPEATABILITY`; see the module docstring)."""
    spec = get_robot(robot)
    return POSE_REPEATABILITY[spec.name] / (RP_PER_SIGMA * lever_per_axis(spec.name))
