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

With these, a geometry-only fit of a simulated UR5e or UR10e predicts held-out poses at about a tenth
to a quarter of a millimetre, as real UR arms do (docs/design.md, Facts: what real arms reach;
`bench/realistic_arm.py` measures it).
"""

from __future__ import annotations

import numpy as np

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
