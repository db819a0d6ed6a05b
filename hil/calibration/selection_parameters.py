"""The parameters a pose design is made for: their expected sizes, and which this station can observe.

Shared by a UR's selection model (`hil.calibration.selection.SelectionModel`) and any other arm's
(`hil.calibration.urdf_selection.UrdfSelectionModel`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.linalg

from hil.arm.kinematics import Kinematics

#: Expected size (rad) of one harmonic coefficient of a joint's angle error, for the "expected" column
#: scaling. An assumption, not a measurement: tens of microradians is what leaves a calibrated UR at the
#: tenth of a millimetre real arms reach (docs/design.md, Facts: what real arms reach) over its reach.
#: O1, the default index, does not depend on it.
JOINT_ERROR_MAGNITUDE = 50e-6


def expected_magnitude(name: str, robot: str) -> float:
    """The expected size of parameter `name` ("expected" column scaling): 0.5 mm and 1 mrad for joint
    and flange placements (the synthetic truths' σ), 1 mm for the SMR offset and the tracker position,
    1 mrad for the tracker orientation, `JOINT_ERROR_MAGNITUDE` for a joint-error harmonic, the typical
    strain-wave compliance for a UR joint's compliance."""
    group, axis = name.split(".")
    if axis.startswith(("cos", "sin")):
        return JOINT_ERROR_MAGNITUDE
    if group == "compliance":
        from hil.arm.physical import typical_compliance

        return float(typical_compliance(robot)[int(axis[1:]) - 1])
    if group == "smr":
        return 1e-3
    if group == "tracker":
        return 1e-3
    return 0.5e-3 if axis.startswith("t") else 1e-3


def drop_unobservable(kinematics: Kinematics, q: np.ndarray, idx: np.ndarray,
                      names: Sequence[str]) -> tuple[np.ndarray, list[str]]:
    """The parameters `idx` less those this station cannot observe, and the names of those dropped.

    The identifiable set is found at a generic point; at the user's SMR guess (on the last joint's axis,
    say) one of them can be truly unobservable for *this* station. Pivoted QR of the unit-norm Jacobian
    at configurations `q` finds it, so it is named in the report rather than making every design look
    singular.
    """
    J = kinematics.jacobian(q, idx).reshape(-1, len(idx))
    J = J / np.linalg.norm(J, axis=0)
    _, r, piv = scipy.linalg.qr(J, mode="economic", pivoting=True)
    d = np.abs(np.diag(r))
    keep = np.sort(piv[d > 1e-7 * d[0]])
    lost = [names[idx[i]] for i in np.sort(piv[d <= 1e-7 * d[0]])]
    return idx[keep], lost
