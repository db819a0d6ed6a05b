"""The robot's manufacturing tolerances as a Gaussian prior on the identified parameters (MAP fit).

Why a prior: a least-squares fit of 27–31 parameters to a few noisy poses chases the noise and can
predict unseen poses worse than the nominal arm (a real UR10e measured by a camera, fit
2.6 mm, held-out 4.8 mm against the nominal's 4.3 mm). A manufactured arm is not arbitrary: each
joint origin and the flange sit within the maker's tolerances of the drawing. Treating those as a
Gaussian prior θ ~ N(θ₀, τ²) and the measurements as r ~ N(0, σ²) gives the maximum-a-posteriori fit

    minimise  Σ‖p_meas − p(θ)‖² + Σᵢ (σ²/τᵢ²)·(θᵢ − θ₀ᵢ)²

so the prior's weight is the measurement noise over the tolerance: with a tracker's 20 µm against
0.5 mm it is 1.6·10⁻³ per parameter against the hundreds a pose set's normal matrix carries (good
data are left as they were), and with a camera's millimetres it is of the order of the data's own
weight (few or noisy poses shrink toward nominal instead of chasing the noise). The posterior
covariance is σ²·(JᵀJ + diag(σ²/τ²))⁻¹.

What carries a prior (the identified set's coordinates, `hil.arm.kinematics`):

* **Joint origins and the flange** — mean 0 (the nominal drawing), σ `TRANSLATION_TOLERANCE` per
  translation axis and `ROTATION_TOLERANCE` per rotation axis. No maker publishes a UR's placement
  tolerances; these are the errors that reproduce what real and simulated UR arms show without
  calibration: UR say uncalibrated arms differ by "multiple millimeters" at full stretch
  (universal-robots.com, "Kinematic Robot Calibration", 2025, cited in
  `mocks.ur.factory_calibration`); a real UR5 (CB3) measured by a Leica tracker predicts held-out
  poses to 1.41 mm with its nominal model (docs/design.md, Facts: what real arms reach); random
  placement errors of 0.5 mm / 1 mrad per axis give 1.8 mm on a UR5e (the synthetic truths,
  `hil.calibration.synthetic.random_truth`, Facts: identification). The tolerance here is twice
  that: hil identifies a reduced set in which one coordinate absorbs the errors of several frames
  (the tracker absorbs joint 1's, the SMR offset the flange's, the parallel joints 2–4 share
  theirs), so one identified coordinate's spread is wider than one frame's — and a prior that is too
  wide only weakens the shrinkage, while one too narrow biases a good fit.
* **Compliance** — mean the joint's typical compliance (`hil.arm.physical.typical_compliance`), σ
  equal to that value: the typical value is itself an assumption (a tenth of the gear's catalogue
  windup), so the prior says only its order of magnitude.
* **Tracker pose and SMR offset** — none: where the user put the tracker and the target is not a
  manufacturing tolerance, and the data determine both well.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hil.arm.chain import Robot, chain_of
from hil.arm.kinematics import ALL_PARAMETER_NAMES, N_ALL_PARAMETERS, N_PARAMETERS, parameter_names

#: Prior standard deviation of a joint origin's or the flange's translation, per axis (m); see the
#: module docstring for its sources and why it is twice the simulated truths' 0.5 mm.
TRANSLATION_TOLERANCE = 1.0e-3
#: Prior standard deviation of a joint origin's or the flange's rotation, per axis (rad).
ROTATION_TOLERANCE = 2.0e-3
#: Prior standard deviation of a joint's compliance as a fraction of its typical value.
COMPLIANCE_SPREAD = 1.0


@dataclass(frozen=True)
class Prior:
    """Gaussian prior on an identified parameter set: mean and standard deviation per parameter.

    `std` is ``inf`` for a free parameter (the tracker pose and SMR offset). `weights(σ)` is the
    diagonal σ²/τ² added to the normal matrix; `offset` is θ − θ₀ for the fit's θ.
    """

    indices: np.ndarray  # into ALL_PARAMETER_NAMES
    mean: np.ndarray  # θ₀ in the identified coordinates (deviation from nominal; compliance absolute)
    std: np.ndarray  # τ, inf where there is no prior

    def weights(self, sigma: float) -> np.ndarray:
        """(n,) σ²/τ²: the prior's rows' squared weights for measurement noise `sigma` (m, per axis)."""
        with np.errstate(divide="ignore"):
            return np.where(np.isfinite(self.std), sigma**2 / self.std**2, 0.0)

    @property
    def constrained(self) -> np.ndarray:
        """(n,) bool: which parameters carry a prior."""
        return np.isfinite(self.std)


#: Prior σ (rad) of a joint-error harmonic's amplitude or a joint's lost motion. No maker publishes a
#: tolerance for them; the realistic arm's are tens of microradians (`hil.arm.joint_physics`), so a σ as
#: loose as the joint origins' rotation tolerance leaves them to the data (the cross-validated term
#: choice, `hil.calibration.joint_error_selection`, decides whether they are fitted at all).
JOINT_ERROR_TOLERANCE = ROTATION_TOLERANCE


def manufacturing_prior(robot: Robot, indices: np.ndarray) -> Prior:
    """The tolerance prior (module docstring) on the identified parameters `indices` of `robot`.

    An arm from its URDF gets the same joint-origin and flange tolerances: no maker of the arms hil
    reads URDFs of publishes its own, and 1 mm / 2 mrad is loose for any machined arm (an assumption,
    the UR's figures reused)."""
    from hil.arm.physical import typical_compliance

    idx = np.asarray(indices, dtype=int)
    if not chain_of(robot).is_ur:
        names = parameter_names(robot)
        std = np.array([np.inf if not names[i].startswith(("joint", "flange"))
                        else TRANSLATION_TOLERANCE if names[i].split(".")[1].startswith("t")
                        else ROTATION_TOLERANCE for i in idx])
        return Prior(idx, np.zeros(len(idx)), std)
    typical = typical_compliance(robot)
    mean = np.zeros(len(idx))
    std = np.full(len(idx), np.inf)
    for k, i in enumerate(idx):
        if i >= N_ALL_PARAMETERS:  # a joint-error harmonic or a lost motion (hil.arm.joint_errors)
            std[k] = JOINT_ERROR_TOLERANCE
            continue
        name = ALL_PARAMETER_NAMES[i]
        if name.startswith(("joint", "flange")):
            std[k] = TRANSLATION_TOLERANCE if name.split(".")[1].startswith("t") else ROTATION_TOLERANCE
        elif i >= N_PARAMETERS:  # compliance.j<i>
            mean[k] = typical[i - N_PARAMETERS]
            std[k] = COMPLIANCE_SPREAD * typical[i - N_PARAMETERS]
    return Prior(idx, mean, std)
