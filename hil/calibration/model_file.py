"""The versioned JSON files that carry a geometry: calibrated models and simulator truths.

``hil-model/1`` is the geometry block plus how the model was obtained: identified parameters with
their standard deviations and covariance, fit statistics, the sha256 of the input data and the
software versions, so a model can always be traced to its measurements. ``hil-truth/1`` is the
geometry block plus the simulated station's noise. Unknown keys are ignored (newer writers may add
some); missing ones are errors naming the key.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
from collections.abc import Mapping
from typing import Any

import numpy as np
import pinocchio as pin

from hil import __version__
from hil.arm.catalog import get_robot
from hil.arm.controller_model import DELTA_KEYS, ControllerCalibration
from hil.arm.geometry import Geometry
from hil.calibration.identification import FitResult
from hil.calibration.synthetic import Noise
from hil.errors import InputError
from hil.files.inputs import MAX_JSON_BYTES, json_number, parse_json, read_input_text
from hil.files.outputs import atomic_write_text

MODEL_FORMAT = "hil-model/1"
RESULT_FORMAT = "hil-result/1"  # a campaign result; it embeds the model
TRUTH_FORMAT = "hil-truth/1"
#: A model's ``controller`` block: the controller's deltas (docs/design.md, Contracts: the
#: controller's own calibration) and how it names its calibration.
CONTROLLER_KEYS: tuple[str, ...] = (*DELTA_KEYS, "checksum", "calibration_status")

#: The quantities of a geometry block's numbers (rows of `hil.files.quantities.QUANTITIES`, where their
#: ranges and sources are): joint origins and the flange are links, the SMR and further reflectors sit
#: on a tool, the tracker stands within its measuring range; angles are link angles.
PLACEMENT_QUANTITIES = {"joints": "link offset", "flange": "link offset", "tracker": "tracker position"}
#: A truth's simulated noise (`noise.*`) and the quantity of each.
NOISE_QUANTITIES = {"tracker_sigma": "tracker noise", "encoder_sigma": "angle noise",
                    "distance_sigma": "tracker noise", "angle_sigma": "angle noise",
                    "standstill_sigma": "angle noise"}


def software_versions() -> dict[str, str]:
    """Versions of hil and of the numerical libraries a result depends on.

    scipy's is read from its installed metadata, not its module: importing scipy only to ask its
    version was 15–25 ms of ``hil identify``, which otherwise does not load it.
    """
    from importlib.metadata import version

    return {"hil": __version__, "pinocchio": pin.__version__, "numpy": np.__version__,
            "scipy": version("scipy")}


#: What the ``parameters`` of a model are (the document says it too, under ``parameter_coordinates``).
PARAMETER_COORDINATES = (
    "joint<i>.tx..rz, flange.* and tracker.* (tx ty tz m, rx ry rz rad) are se(3) log coordinates of "
    "nominal^-1 * identified placement (for the tracker the nominal is the identity: they are the log "
    "coordinates of the tracker pose, not its position or angles, which are 'tracker' and "
    "'tracker_pose'); smr.x/y/z (m) is the SMR centre in the flange frame; compliance.j<i> (rad/Nm) "
    "is joint i's compliance (the 'compliance' block, for the 'payload' block); joint<i>.cos<k>, "
    "joint<i>.sin<k> (rad) are a and b of joint i's harmonic a*cos(k*q) + b*sin(k*q) (the "
    "'joint_errors' block) and lost_motion.j<i> (rad) its lost motion (the 'lost_motion' block); "
    "tool.rx..rz (rad) is the log (rotation vector) of the measured frame's orientation in the flange "
    "frame (the 'tool_rpy' key) and reflector<k>.x/y/z (m) reflector k's centre in the flange frame "
    "(the 'reflectors' key). "
    "std is one standard deviation in the local error coordinates at the solution (T * exp(delta))."
)
_TRACKER_AXES = ("tracker.tx", "tracker.ty", "tracker.tz", "tracker.rx", "tracker.ry", "tracker.rz")


def _xyz_rpy(M: pin.SE3) -> np.ndarray:
    return np.r_[M.translation, pin.rpy.matrixToRpy(M.rotation)]


def tracker_pose(tracker: pin.SE3, names: list[str] | tuple[str, ...] = (),
                 covariance: Any = None) -> dict[str, Any]:
    """The tracker frame in the robot base frame in plain terms, with standard deviations.

    ``xyz`` (m) and ``rpy`` (rad, URDF convention R = Rz(yaw)·Ry(pitch)·Rx(roll)), as the geometry
    block's ``tracker``; ``xyz_std`` and ``rpy_std`` propagate the fit's covariance of the
    ``tracker.tx … tracker.rz`` parameters (se(3) log coordinates, local at the solution) to first
    order. A coordinate the fit did not identify counts as exact (σ 0); without a covariance the
    standard deviations are None.
    """
    value = _xyz_rpy(tracker)
    out: dict[str, Any] = {"xyz": value[:3].tolist(), "rpy": value[3:].tolist(), "xyz_std": None,
                           "rpy_std": None}
    picked = [(k, names.index(n)) for k, n in enumerate(_TRACKER_AXES) if n in names]
    if covariance is None or not picked:
        return out
    C = np.asarray(covariance, dtype=float)
    h = 1e-6
    J = np.zeros((6, len(picked)))
    for col, (k, _) in enumerate(picked):
        d = np.zeros(6)
        d[k] = h
        diff = _xyz_rpy(tracker * pin.exp6(d)) - _xyz_rpy(tracker * pin.exp6(-d))
        diff[3:] = (diff[3:] + np.pi) % (2 * np.pi) - np.pi  # an angle crossing ±π
        J[:, col] = diff / (2 * h)
    sub = C[np.ix_([i for _, i in picked], [i for _, i in picked])]
    std = np.sqrt(np.maximum(np.diag(J @ sub @ J.T), 0.0))
    out["xyz_std"], out["rpy_std"] = std[:3].tolist(), std[3:].tolist()
    return out


def prior_block(fit: FitResult) -> dict[str, Any] | None:
    """The model's ``fit.prior``: the MAP fit's tolerances and the noise its weights used (None: a
    plain least-squares fit)."""
    from hil.calibration import prior as tolerances

    if fit.prior is None:
        return None
    return {"kind": "manufacturing tolerances (hil.calibration.prior)",
            "translation_tolerance": tolerances.TRANSLATION_TOLERANCE,
            "rotation_tolerance": tolerances.ROTATION_TOLERANCE,
            "compliance_spread": tolerances.COMPLIANCE_SPREAD,
            "parameters": int(np.sum(fit.prior.constrained)), "sigma": fit.sigma}


def model_document(fit: FitResult, validation: dict[str, Any] | None = None,
                   controller: Mapping[str, Any] | None = None,
                   cross_validation: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The ``hil-model/1`` JSON document of an identification result.

    `cross_validation`: the fit's ``CrossValidation.as_dict()``, kept as the ``cross_validation`` block;
    its ``better_than_nominal`` is repeated at the top level, where `hil export` and `hil compensate`
    look before they hand the model out.

    `controller`: the controller's own model the campaign ran with (its KinematicsInfo record, see
    `hil.campaign.controller`), kept as the ``controller`` block — the deltas
    (docs/design.md, Contracts: the controller's own calibration) plus the
    controller's per-joint ``checksum`` and ``calibration_status`` — so the model can be compared
    with, and exported beside, the one the arm moves with (`model_controller` reads it back).
    """
    doc: dict[str, Any] = {"format": MODEL_FORMAT, **fit.geometry.to_dict()}
    doc["parameters"] = [
        {"name": name, "value": float(v), "std": float(s)}
        for name, v, s in zip(fit.names, fit.values, fit.std, strict=True)
    ]
    doc["parameter_coordinates"] = PARAMETER_COORDINATES
    doc["tracker_pose"] = tracker_pose(fit.geometry.tracker, fit.names, fit.covariance)
    doc["covariance"] = {"parameters": fit.names, "matrix": fit.covariance.tolist()}
    doc["fit"] = {
        "poses": len(fit.used),
        "used": int(fit.used.sum()),
        "rms": fit.rms,
        "max": fit.max_error,
        "sigma": fit.sigma,
        "initial_rms": fit.initial_rms,
        "iterations": fit.iterations,
        "condition": fit.condition,
        "seconds": fit.seconds,
        "rejected": [{"pose": r.index, "line": r.line, "residual": r.residual, "p_value": r.p_value}
                     for r in fit.rejected],
        "correlated": [{"a": c.a, "b": c.b, "rho": c.rho} for c in fit.correlated],
        "prior": prior_block(fit),
    }
    if fit.pose_fit is not None:  # a 6-D or several-reflector fit (hil.calibration.pose_identification)
        doc["fit"]["pose_fit"] = fit.pose_fit.as_dict(fit.used)
    if fit.joint_error_choice is not None:
        doc["joint_error_selection"] = fit.joint_error_choice.as_dict()
    if cross_validation is not None:
        doc["cross_validation"] = dict(cross_validation)
        doc["better_than_nominal"] = bool(cross_validation["better_than_nominal"])
    if validation is not None:
        doc["validation"] = validation
    if controller is not None:
        doc["controller"] = {key: controller.get(key) for key in CONTROLLER_KEYS}
    doc["input"] = {"file": os.path.basename(fit.source), "sha256": fit.sha256}
    doc["software"] = software_versions()
    doc["created"] = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    return doc


def refuse_worse_than_nominal(doc: Mapping[str, Any], source: str, force: bool, verb: str,
                              remedy: str | None = None) -> str | None:
    """Refuse to hand out a model cross-validation did not show better than the nominal (or the
    controller's) model: InputError naming the file and the figures, unless `force`, when the same
    sentence comes back as a warning to print. A model without the verdict (older hil) passes.
    `remedy` replaces "give --force to <verb> it anyway" where there is no --force (the TUI).
    """
    if doc.get("better_than_nominal") is not False:
        return None
    block = doc.get("cross_validation") if isinstance(doc.get("cross_validation"), Mapping) else {}

    def rms(key: str) -> str:
        value = (block.get(key) or {}).get("rms") if isinstance(block.get(key), Mapping) else None
        return f"{value * 1e3:.4f} mm" if isinstance(value, int | float) else "unknown"

    figures = f"calibrated {rms('calibrated')}, nominal {rms('nominal')}"
    if isinstance(block.get("controller"), Mapping):
        figures += f", controller's model {rms('controller')}"
    said = (f"{source}: better_than_nominal is false: by cross-validation ({figures}) this model does not "
            f"predict the arm better than the nominal or the controller's own model")
    if not force:
        raise InputError(f"{said}; refused ({remedy or f'give --force to {verb} it anyway'})")
    return said


def model_controller(doc: Mapping[str, Any], source: str = "model") -> ControllerCalibration | None:
    """The controller's own model a model file keeps (its ``controller`` block), or None without one.

    A malformed block is an InputError naming the file and the field (`ControllerCalibration.from_dict`).
    """
    block = doc.get("controller")
    if block is None:
        return None
    return ControllerCalibration.from_dict(block, f"{source}: controller")


def truth_document(truth: Geometry, noise: Noise,
                   controller: ControllerCalibration | None = None) -> dict[str, Any]:
    """The ``hil-truth/1`` JSON document of a simulated arm (with its controller's deltas if given)."""
    doc = {"format": TRUTH_FORMAT, **truth.to_dict(), "noise": noise.as_dict()}
    if controller is not None:
        doc["controller"] = controller.to_dict()
    return doc


def truth_controller(doc: Mapping[str, Any], source: str = "truth") -> ControllerCalibration | None:
    """The simulated controller's own calibration a truth document names, or None when it names none.

    None lets the simulator draw one for the arm (docs/design.md, Contracts: the controller's own
    calibration); a
    malformed block is an InputError naming the file and the field.
    """
    block = doc.get("controller")
    if block is None:
        return None
    return ControllerCalibration.from_dict(block, f"{source}: controller")


def write_json(path: str | os.PathLike[str], doc: dict[str, Any]) -> None:
    """Write a JSON document atomically (floats at full precision)."""
    atomic_write_text(path, json.dumps(doc, indent=2) + "\n")


def read_json(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Parse a JSON file; InputError naming the file and line when it is not valid JSON."""
    name = str(path)
    doc = parse_json(read_input_text(path, "a JSON file", line_based=False, limit=MAX_JSON_BYTES), name)
    if not isinstance(doc, dict):
        raise InputError(f"{name}: expected a JSON object")
    return doc


def load_geometry(path: str | os.PathLike[str],
                  formats: tuple[str, ...] = (MODEL_FORMAT, TRUTH_FORMAT)) -> tuple[Geometry, dict]:
    """The geometry in a model or truth file, and the whole document.

    Where a model is accepted, a campaign result (``hil-result/1``, what ``hil calibrate --out``
    writes) is accepted too: it embeds the model, and an engineer should not have to dig it out.
    """
    doc = read_json(path)
    fmt = doc.get("format")
    if fmt == RESULT_FORMAT and MODEL_FORMAT in formats:
        model = doc.get("model")
        if not isinstance(model, dict):
            raise InputError(f"{path}: the campaign result holds no model (status {doc.get('status')!r})")
        doc, fmt = model, model.get("format")
        prefix = "model."
    else:
        prefix = ""
    if fmt not in formats:
        raise InputError(f"{path}: field 'format' is {fmt!r}, expected {' or '.join(formats)}")
    check_geometry_block(doc, str(path), prefix)
    return Geometry.from_dict(doc, source=str(path)), doc


def check_geometry_block(doc: dict[str, Any], source: str, prefix: str = "") -> None:
    """Refuse a geometry block whose numbers are not real, finite, physically plausible numbers.

    `Geometry.from_dict` takes anything float() takes, so `true`, "1" and 1e308 would become a model
    that drives the arm or the planner; this names the first bad field by its path in the document
    (``model.json: joints[2].xyz[0]: expected a number, got true``). Missing keys and wrong shapes are
    left to `Geometry.from_dict`, which already names them.
    """
    def numbers(value: Any, field: str, quantity: str) -> None:
        if isinstance(value, list):
            for i, v in enumerate(value):
                json_number(v, f"{source}: {prefix}{field}[{i}]", quantity)

    def placement(value: Any, field: str, quantity: str) -> None:
        if isinstance(value, dict):
            numbers(value.get("xyz"), f"{field}.xyz", quantity)
            numbers(value.get("rpy"), f"{field}.rpy", "link angle")

    robot = doc.get("robot")
    if isinstance(robot, str) and doc.get("urdf") is None:  # an arm from its URDF is named by it
        try:
            get_robot(robot)
        except InputError as exc:  # the catalog's message does not know which file it came from
            raise InputError(f"{source}: {prefix}robot: {exc}") from None
    joints = doc.get("joints")
    if isinstance(joints, list):
        for i, joint in enumerate(joints):
            placement(joint, f"joints[{i}]", PLACEMENT_QUANTITIES["joints"])
    placement(doc.get("flange"), "flange", PLACEMENT_QUANTITIES["flange"])
    numbers(doc.get("smr"), "smr", "tool offset")
    numbers(doc.get("tool_rpy"), "tool_rpy", "link angle")
    reflectors = doc.get("reflectors")
    if isinstance(reflectors, list):
        for k, row in enumerate(reflectors):
            numbers(row, f"reflectors[{k}]", "tool offset")
    placement(doc.get("tracker"), "tracker", PLACEMENT_QUANTITIES["tracker"])


def load_truth(path: str | os.PathLike[str]) -> tuple[Geometry, Noise]:
    """A simulator truth: geometry and noise (the noise block is required)."""
    geometry, doc = load_geometry(path, (TRUTH_FORMAT,))
    block = doc.get("noise")
    if not isinstance(block, dict):
        raise InputError(f"{path}: missing field 'noise'")
    values: dict[str, float | None] = {}
    for key in ("tracker_sigma", "encoder_sigma"):
        if key not in block:
            raise InputError(f"{path}: missing field 'noise.{key}'")
        if key == "tracker_sigma" and block[key] is None:  # null: the tracker's distance-dependent model
            values[key] = None
            continue
        values[key] = json_number(block[key], f"{path}: noise.{key}", NOISE_QUANTITIES[key])
    # optional: the tracker model's figures (hil.calibration.tracker_noise) otherwise, and no
    # stop-to-stop scatter of the joints (a truth written before the simulated arm had one)
    for key in ("distance_sigma", "angle_sigma", "standstill_sigma"):
        if key in block:
            values[key] = json_number(block[key], f"{path}: noise.{key}", NOISE_QUANTITIES[key])
    return geometry, Noise(**values)  # type: ignore[arg-type]
