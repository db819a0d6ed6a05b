"""The pose test's figures: commanded positions in the tracker's frame, AP and RP per pose and mode.

The tracker measures the SMR in its own frame; the commanded positions are in the robot base frame.
How one is brought into the other says what AP means, so the result says which was used:

* **model** (a calibrated model was given): its tracker pose and SMR offset. The SMR offset is also
  the tool of every target, so a pose's commanded position is the cube point itself, for both modes.
* **registered** (no model: the uncompensated test only): the tracker pose and SMR offset fitted to
  the measured points with the controller's own model (`hil.calibration.identification.register`
  with the controller's arm). The fit takes up whatever error a rigid motion of the whole test and a
  shift of the SMR explain, so AP is then a lower bound of the controller's accuracy in its own frame;
  a pose's commanded position is what the controller's model puts the fitted SMR at, at its joints.

Orientation accuracy and repeatability are not given: one SMR measures a position only.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from hil.arm.geometry import Geometry, pose_to_dict
from hil.arm.kinematics import Kinematics
from hil.calibration.identification import register
from hil.calibration.measurements import Measurements
from hil.campaign.steps import PoseRecord
from hil.errors import HilError
from hil.verify.accuracy import pose_accuracy
from hil.verify.cube import CYCLE_ORDER, POSE_NAMES, pose_index
from hil.verify.design import UNCOMPENSATED, Design

FORMAT = "hil-verification/1"
ORIENTATION = "not measured: one SMR gives position only"
STANDARD = ("ISO 9283:1998 pose accuracy AP (§7.2.1) and pose repeatability RP (§7.2.2), position "
            "only; test cube and poses P1-P5 as in §6.2-6.3")
FRAME_NOTES = {
    "model": "commanded positions put into the tracker frame by the model's tracker pose and SMR offset",
    "registered": ("tracker pose and SMR offset fitted to the measured points with the controller's own "
                   "model, which takes up any error a rigid motion explains (AP is a lower bound)"),
}


class VerificationError(HilError):
    """Too little was measured to give the figures (every visit of a pose skipped)."""


@dataclass(frozen=True)
class Frame:
    """How commanded positions reach the tracker frame (see the module docstring)."""

    source: str  # "model" or "registered"
    geometry: Geometry  # arm (model's or controller's), SMR offset and tracker pose

    def commanded(self, design: Design, visit_mode: str, name: str) -> np.ndarray:
        """The commanded SMR position of pose `name` in `visit_mode`, tracker frame."""
        if self.source == "model":
            T = self.geometry.tracker
            return T.rotation.T @ (design.positions()[pose_index(name)] - T.translation)
        return Kinematics(self.geometry).points(design.joints[visit_mode][pose_index(name)])[0]

    def to_dict(self) -> dict[str, Any]:
        return {"source": self.source, "tracker": pose_to_dict(self.geometry.tracker),
                "smr": [float(v) for v in self.geometry.smr], "note": FRAME_NOTES[self.source]}


def model_frame(model: Geometry) -> Frame:
    return Frame("model", model)


def registered_frame(design: Design, records: Mapping[int, PoseRecord], controller: Geometry) -> Frame:
    """The tracker pose and SMR fitted to the measured points with the controller's model."""
    pts = sorted(records.values(), key=lambda r: r.index)
    if len(pts) < 4:
        raise VerificationError(f"cannot register the tracker: {len(pts)} points measured, 4 needed")
    meas = Measurements(np.array([r.q for r in pts]), np.array([r.p for r in pts]),
                        np.array([r.index for r in pts]), "verification", "")
    located = register(meas, design.robot, design.tool, arm=controller)
    return Frame("registered", located)


def deviation(design: Design, frame: Frame) -> Any:
    """For the live display: each point's distance from its pose's commanded position (m)."""
    by_index = {v.index: v for v in design.visits()}

    def distance(record: PoseRecord) -> float | None:
        visit = by_index.get(record.index)
        if visit is None:
            return None
        return float(np.linalg.norm(record.p - frame.commanded(design, visit.mode, visit.pose)))

    return distance


def _mode(design: Design, records: Mapping[int, PoseRecord], frame: Frame, mode: str) -> dict[str, Any]:
    """AP and RP of every pose of one mode, in `frame`."""
    visits = design.visits()
    to_base = frame.geometry.tracker.rotation
    rows = []
    for name in POSE_NAMES:
        mine = [records[v.index] for v in visits if v.mode == mode and v.pose == name and v.index in records]
        commanded = frame.commanded(design, mode, name)
        row: dict[str, Any] = {"pose": name}
        if len(mine) >= 2:
            attained = np.array([r.p for r in mine])
            row.update(pose_accuracy(attained, commanded, to_base).as_dict())
            row["offsets"] = ((attained - commanded) @ to_base.T).tolist()  # base axes, m
        else:
            row.update({"n": len(mine), "commanded": [float(v) for v in commanded],
                        "note": "fewer than 2 attained positions: no AP/RP"})
        rows.append(row)
    measured = [r for r in rows if "AP_P" in r]
    if not measured:
        raise VerificationError(f"{mode}: no pose was measured at least twice")
    return {"poses": rows, "AP_max": max(r["AP_P"] for r in measured),
            "RP_max": max(r["RP_l"] for r in measured),
            "AP_mean": float(np.mean([r["AP_P"] for r in measured]))}


def evaluate(design: Design, records: Mapping[int, PoseRecord], frame: Frame,
             skipped: Mapping[int, str] | None = None, controller: Geometry | None = None) -> dict[str, Any]:
    """The verification's figures (``hil-verification/1`` without the run's provenance).

    With a model's frame and the controller's model (`controller`), the uncompensated poses are also
    judged in the controller's own frame (``own_frame``: registered on them alone, see
    `registered_frame`): the model's frame holds the base frame where hil's calibration put it, and the
    part of the uncompensated AP that is only the two models' different base frames (the height and
    zero angle of joint 1, which no tracker measurement fixes) shows as the difference between the two.
    """
    visits = design.visits()
    doc: dict[str, Any] = {
        "format": FORMAT,
        "standard": STANDARD,
        "robot": design.robot,
        "cube": {**design.cube.to_dict(), "diagonal": design.cube.diagonal, "plane": "C1-C2-C7-C8"},
        "poses": {name: [float(v) for v in p] for name, p in zip(POSE_NAMES, design.positions(),
                                                                   strict=True)},
        "tool": {"smr": [float(v) for v in design.tool],
                 "orientation": pose_to_dict(pin.SE3(np.asarray(design.rotation), np.zeros(3)))["rpy"],
                 "faces": {"tracker": [float(v) for v in design.tracker], "from": design.tracker_source}},
        "cycles": design.cycles,
        "cycle_order": list(CYCLE_ORDER),
        "modes": list(design.modes),
        "frame": frame.to_dict(),
        "orientation": ORIENTATION,
        "results": {mode: _mode(design, records, frame, mode) for mode in design.modes},
    }
    if controller is not None and frame.source == "model" and UNCOMPENSATED in design.modes:
        own = {i: r for i, r in records.items()
               if any(v.index == i and v.mode == UNCOMPENSATED for v in visits)}
        mine = registered_frame(design, own, controller)
        doc["own_frame"] = {"mode": UNCOMPENSATED, "frame": mine.to_dict(),
                            **_mode(design, own, mine, UNCOMPENSATED)}
    by_index = {v.index: v for v in visits}
    doc.update({
        "visits": len(visits),
        "measured": sum(1 for v in visits if v.index in records),
        "skipped": [{"index": i, "mode": by_index[i].mode, "pose": by_index[i].pose, "reason": why}
                    for i, why in sorted((skipped or {}).items()) if i in by_index],
    })
    return doc


def summary(doc: Mapping[str, Any]) -> str:
    """One line: the worst pose's AP and RP of each mode, in millimetres."""
    parts = [f"{mode} AP {r['AP_max'] * 1e3:.3f} mm, RP {r['RP_max'] * 1e3:.3f} mm"
             for mode, r in doc["results"].items()]
    return f"ISO 9283 over {doc['cycles']} cycles (worst pose): " + "; ".join(parts)
