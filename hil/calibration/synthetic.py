"""Synthetic truths and measurements: a robot with hidden errors, for tests, benchmarks and demos.

The same generator seeds the simulators' random "truth", so a benchmark and a simulated station
describe an arm the same way: every joint origin and the flange carry a random 6-D placement error
(σ 0.5 mm per translation axis, 1 mrad per rotation axis by default), the SMR sits a few centimetres
off the flange axis, and the tracker stands 2–4 m from the base facing it.

Unless asked for a rigid arm, the truth is a real one
(docs/design.md, Contracts: non-geometric errors): its joints
are compliant (UR's typical strain-wave stiffness, `hil.arm.physical.typical_compliance`, each joint
0.8–1.2 times it), it carries the SMR, its nest and an adaptor plate (`smr_payload`), and it warms up
as it runs (`Thermal` defaults). Its encoders read with a UR joint's noise (`ENCODER_SIGMA`).

Unless asked for the *ideal* arm (geometry, compliance, payload
and warm-up only), its link angles also differ from its encoders by angle-dependent joint errors and
lost motion of the sizes a UR joint's output encoder leaves (`hil.arm.joint_physics`, which cites
them): what keeps a real, calibrated UR at tenths of a millimetre rather than the hundredths an ideal
arm reaches (docs/design.md, Facts: what real arms reach). Lost motion needs the direction each joint
last moved in: `measure` and `true_points` take it (`directions`; without, none is applied, as if the
SMR sat in the middle of its lost-motion band).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from hil.arm.catalog import get_robot
from hil.arm.chain import Chain, Robot, chain_of
from hil.arm.geometry import Geometry, look_at_tracker
from hil.arm.joint_errors import motion_directions
from hil.arm.joint_physics import IDEAL_BY_DEFAULT, typical_joint_errors, typical_lost_motion
from hil.arm.kinematics import Kinematics, apply_update, parameter_layout, refuse_non_ur
from hil.arm.payload import Payload
from hil.arm.physical import typical_compliance
from hil.arm.thermal import Thermal
from hil.calibration.tracker_noise import ANGLE_SIGMA, DISTANCE_SIGMA, perturb_points

DEFAULT_SMR = (0.0, 0.0, 0.045)  # flange-mounted SMR nest, 45 mm out along the flange axis

#: Standard deviation (rad) of one joint reading of a UR arm (RTDE ``actual_q`` at rest). We found no
#: published figure for UR's encoders, but their repeatability bounds it: the controller holds each
#: joint where its encoder reads it (a UR joint senses its angle on both sides of the gear, UR's
#: patent WO2015131904), so reading noise shows in the pose repeatability, ±0.03 mm for the UR3e/UR5e
#: and ±0.05 mm for the UR10e/UR16e (ISO 9283; UR e-Series technical specifications). ISO 9283's
#: RP = l̄ + 3·S_l is 3.6 σ for an isotropic Gaussian scatter of σ per axis, so σ ≤ 8 µm; the six
#: joints of a UR5e in a working pose move the flange by √Σr² ≈ 0.9 m per radian, about 0.5 m per
#: axis, so a joint may read at most 1.6e-5 rad noisy. Friction and servo error take most of that
#: budget (the simulated arm's stop-to-stop error, `hil.arm.joint_physics.standstill_sigma`, is that
#: whole budget), so a third of it is the encoders': 5e-6 rad, about one count of a 20-bit absolute encoder
#: (2π/2²⁰ = 6.0e-6 rad).
ENCODER_SIGMA = 5e-6

#: A tracker target on the flange (kg, m): a 1.5" SMR (a 38.1 mm steel ball, 0.23 kg solid, about
#: 0.18 kg hollowed for its cube corner) in a magnetic nest (about 0.1 kg), on an aluminium adaptor
#: plate Ø100 × 12 mm bolted to the ISO 9409-1-50-4-M6 tool flange (π·0.05²·0.012 m³ × 2700 kg/m³
#: ≈ 0.25 kg, its centre 6 mm out).
SMR_AND_NEST_MASS = 0.28
ADAPTOR_PLATE_MASS = 0.25
ADAPTOR_PLATE_COM = (0.0, 0.0, 0.006)
#: Each joint's compliance is UR's typical value times a factor drawn from this range: a strain-wave
#: gear's catalogue stiffness is a typical value, not a limit, and joints of one size differ by tens of
#: percent (their bearings, preload and assembly add their own compliance).
COMPLIANCE_SPREAD = (0.8, 1.2)


def smr_payload(smr: np.ndarray) -> Payload:
    """What an arm carrying a tracker target weighs at the flange: the plate plus the nest at `smr`."""
    mass = SMR_AND_NEST_MASS + ADAPTOR_PLATE_MASS
    com = (SMR_AND_NEST_MASS * np.asarray(smr, dtype=float)
           + ADAPTOR_PLATE_MASS * np.asarray(ADAPTOR_PLATE_COM)) / mass
    return Payload(mass, tuple(float(v) for v in com))  # type: ignore[arg-type]


@dataclass(frozen=True)
class Noise:
    """Measurement noise of a simulated station.

    By default the points err as a laser tracker's do, more the farther they are
    (`hil.calibration.tracker_noise`: the AT960's MPE, the same model the GeoCOM and emScon simulators
    use): along the beam by `distance_sigma`, across it by `angle_sigma` per metre. A `tracker_sigma`
    replaces that by a flat isotropic σ per axis — another instrument (a camera's millimetres, hil
    synth --noise) or a benchmark that fixes its noise.
    """

    tracker_sigma: float | None = None  # m, per axis (isotropic Gaussian); None: the tracker's model
    encoder_sigma: float = ENCODER_SIGMA  # rad, per joint reading (a UR joint's, see ENCODER_SIGMA)
    distance_sigma: float = DISTANCE_SIGMA  # m, along the beam (tracker model only)
    angle_sigma: float = ANGLE_SIGMA  # rad, of each angle (tracker model only)
    # rad, σ of each joint's stop-to-stop position error, seen by its encoder (the simulated arm's
    # repeatability, `hil.arm.joint_physics.standstill_sigma`); offline measurements take the joints
    # as they stand, so only the robot simulator, which is commanded, uses it
    standstill_sigma: float = 0.0

    def perturb(self, points: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """(N, 3) tracker-frame `points` as measured: with the flat σ, or as the tracker reads them."""
        P = np.atleast_2d(np.asarray(points, dtype=float))
        if self.tracker_sigma is not None:
            return P + rng.normal(0.0, self.tracker_sigma, size=P.shape)
        return perturb_points(P, rng, self.distance_sigma, self.angle_sigma)

    def as_dict(self) -> dict[str, float | None]:
        """The truth file's ``noise`` block (docs/design.md): ``tracker_sigma`` null for the tracker model."""
        return {"tracker_sigma": self.tracker_sigma, "encoder_sigma": self.encoder_sigma,
                "distance_sigma": self.distance_sigma, "angle_sigma": self.angle_sigma,
                "standstill_sigma": self.standstill_sigma}


def chain_reach(chain: Chain) -> float:
    """An arm's reach from its chain (m): the sum of its origins' and flange's offsets, an upper bound
    of the flange's distance from the first joint, for an arm without a datasheet figure here."""
    return float(sum(np.linalg.norm(M.translation) for M in (*chain.origins[1:], chain.flange)))


def random_truth(robot: Robot, rng: np.random.Generator, *, translation_sigma: float = 0.5e-3,
                 rotation_sigma: float = 1e-3, smr: np.ndarray | None = None,
                 tracker_distance: tuple[float, float] = (2.0, 4.0), rigid: bool = False,
                 ideal: bool = IDEAL_BY_DEFAULT) -> Geometry:
    """A realistic true arm: nominal + random placement errors, an SMR and a tracker pose, and (unless
    `rigid`) compliant joints, the SMR's payload and thermal growth, and (unless `rigid` or `ideal`)
    angle-dependent joint errors and lost motion (`hil.arm.joint_physics`).

    The non-geometric blocks are drawn from a child of `rng` (`Generator.spawn` leaves its stream where
    it is), so a seed gives the same geometry either way, and the caller's later draws (poses, noise)
    are the same too: a rigid, an ideal and a realistic arm of one seed differ only by those blocks
    (the joint errors are drawn after the compliance, so the ideal and the realistic arm share it).

    An arm from its URDF (a `Chain`) has only the geometric truth: `rigid` must be set, since its
    compliance, joint errors and warm-up are modelled for URs only.
    """
    chain = chain_of(robot)
    if not rigid:
        refuse_non_ur(chain, "a realistic (compliant, warming) truth")
    reach = get_robot(chain.name).reach if chain.is_ur else chain_reach(chain)
    if smr is None:
        smr = np.array([rng.uniform(-0.04, 0.04), rng.uniform(-0.04, 0.04), rng.uniform(0.02, 0.06)])
    heading = rng.uniform(-np.pi, np.pi)
    dist = rng.uniform(*tracker_distance) * max(reach / 0.85, 1.0) ** 0.5
    position = np.array([dist * np.cos(heading), dist * np.sin(heading), rng.uniform(-0.3, 0.6)])
    tracker = look_at_tracker(position) * pin.exp6(np.r_[np.zeros(3), rng.normal(0, 0.02, 3)])
    lay = parameter_layout(chain.dof)
    errors = np.zeros(lay.size)
    placements = np.r_[np.tile(np.r_[np.full(3, translation_sigma), np.full(3, rotation_sigma)],
                               chain.dof + 1)]
    errors[: placements.size] = rng.normal(0.0, placements)
    errors[lay.smr] = 0.0
    errors[lay.tracker] = 0.0
    truth = apply_update(Geometry.nominal(robot if chain.is_ur else chain, smr=smr, tracker=tracker),
                         errors)
    if rigid:
        return truth
    spec = get_robot(chain.name)
    child = rng.spawn(1)[0]
    truth.compliance = typical_compliance(spec.name) * child.uniform(*COMPLIANCE_SPREAD, 6)
    truth.payload = smr_payload(truth.smr)
    # docs/design.md's example warm-up (Facts: thermal growth): aluminium links (2.3e-5 /K), 6 K in a
    # 15-min time constant. UR joints
    # do warm as they run: a UR3's and a UR5's viscous friction fell by a fifth "under rising joint
    # temperatures" over repeated runs of one trajectory (Robotics 2021, 10(3), 83,
    # doi:10.3390/robotics10030083), and UR has a cold arm warm up with slow motions before full speed
    # ("Robot start-up in cold environments", universal-robots.com).
    truth.thermal = Thermal()
    if not ideal:
        truth.joint_errors = typical_joint_errors(spec.name, child)
        truth.lost_motion = typical_lost_motion(spec.name, child)
    return truth


def random_configurations(robot: Robot, count: int, rng: np.random.Generator) -> np.ndarray:
    """Joint vectors uniformly spread over ±π per joint (inside every UR joint limit); for an arm from
    its URDF uniformly within its limits (a revolute joint's clipped to ±π, `Chain.sampling_range`)."""
    chain = chain_of(robot)
    if chain.is_ur:
        return rng.uniform(-np.pi, np.pi, size=(count, 6))
    lo, hi = chain.sampling_range()
    return rng.uniform(lo, hi, size=(count, chain.dof))


def measure(truth: Geometry, q: np.ndarray, noise: Noise, rng: np.random.Generator,
            times: np.ndarray | None = None, directions: np.ndarray | None = None
            ) -> tuple[np.ndarray, np.ndarray]:
    """Simulated readings at configurations `q`: (joint readings, tracker points with noise).

    `times` (s of running, one per pose) warm an arm with a thermal block: pose i sees
    ``truth.warmed(times[i])``. Without `times` every pose sees the cold arm. `directions` (6 or
    (N, 6), each −1, 0 or +1: the sign of each joint's last motion before the reading) apply the
    truth's lost motion (`approach_directions` gives them for a sequence of poses).
    """
    q = np.asarray(q, dtype=float)
    p = noise.perturb(true_points(truth, q, times, directions), rng)
    q_read = q + rng.normal(0.0, noise.encoder_sigma, size=q.shape) if noise.encoder_sigma else q.copy()
    return q_read, p


def true_points(truth: Geometry, q: np.ndarray, times: np.ndarray | None = None,
                directions: np.ndarray | None = None) -> np.ndarray:
    """(N, 3) noise-free SMR positions in the tracker frame, each pose on the arm as warm as at its time
    and, with `directions` (as in `measure`), lagging by the truth's lost motion."""
    Q = np.atleast_2d(np.asarray(q, dtype=float))
    D = None if directions is None else np.broadcast_to(np.asarray(directions, dtype=float), Q.shape)
    if times is None or truth.thermal is None:
        return Kinematics(truth).points(Q, directions=D)
    t = np.asarray(times, dtype=float).reshape(-1)
    if t.shape != (len(Q),):
        raise ValueError(f"times: expected one running time per pose ({len(Q)}), got {t.size}")
    out = np.empty((len(Q), 3))
    for ti in np.unique(t):  # one model per distinct time: poses measured together share it
        rows = t == ti
        out[rows] = Kinematics(truth.warmed(float(ti))).points(Q[rows],
                                                              directions=None if D is None else D[rows])
    return out


def approach_directions(q: np.ndarray, start: np.ndarray | None = None) -> np.ndarray:
    """(N, 6) each joint's last direction of motion on arriving at each of poses `q` visited in order
    (straight moves from `start`, else from the first pose: its directions are then 0, none known)."""
    Q = np.atleast_2d(np.asarray(q, dtype=float))
    previous = Q[0] if start is None else np.asarray(start, dtype=float)
    out = np.zeros_like(Q)
    last: np.ndarray | None = None
    for n, qn in enumerate(Q):
        last = motion_directions(previous, qn, last)
        out[n] = last
        previous = qn
    return out
