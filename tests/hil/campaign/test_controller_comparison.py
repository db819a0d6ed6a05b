"""Issue 14: a campaign keeps the controller's own kinematic model and says how far it is from the truth.

The controller's model comes from the driver's KinematicsInfo (faked here with the interface H1's
`drivers.robot.kinematics_info.KinematicsInfo` has: checksum, dh_theta … dh_alpha, calibration_status).
Its figures on the validation poses are checked against a hand computation (the DH chain multiplied
out with numpy), and against what the tracker cannot see: a controller whose deltas only move the base
frame or turn the flange about its axis scores exactly as the nominal arm does.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.arm.controller_model import ControllerCalibration
from hil.arm.geometry import Geometry
from hil.calibration.identification import register, validate
from hil.calibration.measurements import Measurements
from hil.calibration.synthetic import Noise, measure, random_truth
from hil.campaign.calibration_plan import Choice, calibration_plan
from hil.campaign.controller import controller_calibration, controller_record, controller_validation
from hil.campaign.events import ControllerModel, EventBus, RunStarted, ValidationDone
from hil.campaign.runner import run_campaign
from hil.campaign.steps import Acquire, Emit, PoseRecord, dry_run
from hil.report.result import result_document
from hil.station.config import default_config
from tests.hil.campaign.fakes import FakeArm, FakeTracker, visible_poses

CALIBRATION = ControllerCalibration(
    delta_theta=[2e-4, -1e-3, 5e-4, 3e-4, -2e-4, 1e-3], delta_a=[1e-4, 3e-4, -2e-4, 1e-4, 0.0, 0.0],
    delta_d=[5e-4, 0.21, -0.2105, 4e-4, -3e-4, 2e-4], delta_alpha=[1e-3, -4e-4, 6e-4, 2e-4, -5e-4, 0.0])


def fake_kinematics(calibration: ControllerCalibration, robot: str = "ur5e", status: int = 2) -> Any:
    """What the driver's KinematicsInfo carries: the full DH table, checksums, the status."""
    theta, a, d, alpha = calibration.dh(robot)
    return SimpleNamespace(checksum=tuple(calibration.checksums()), dh_theta=tuple(theta), dh_a=tuple(a),
                           dh_d=tuple(d), dh_alpha=tuple(alpha), calibration_status=status)


# --- the record kept with the campaign -------------------------------------------------------------
def test_the_record_holds_what_the_controller_said_and_the_deltas():
    kin = fake_kinematics(CALIBRATION)
    record = controller_record("ur5e", kin)
    assert record["checksum"] == CALIBRATION.checksums() and record["calibration_status"] == 2
    assert record["dh_d"] == list(kin.dh_d)
    back = controller_calibration(record)
    for key in ("delta_theta", "delta_a", "delta_d", "delta_alpha"):
        assert np.allclose(getattr(back, key), getattr(CALIBRATION, key), atol=1e-15, rtol=0)
    as_dict = {k: list(v) if isinstance(v, tuple) else v for k, v in vars(kin).items()}
    assert controller_record("ur5e", as_dict) == record  # KinematicsInfo.as_dict() works the same


@pytest.mark.parametrize("broken", [None, SimpleNamespace(), SimpleNamespace(
    checksum=(1,) * 6, dh_theta=(0.0,) * 5, dh_a=(0.0,) * 6, dh_d=(0.0,) * 6, dh_alpha=(0.0,) * 6,
    calibration_status=1), {"dh_theta": [float("nan")] + [0.0] * 5, "dh_a": [0.0] * 6,
                            "dh_d": [0.0] * 6, "dh_alpha": [0.0] * 6}])
def test_no_record_without_a_usable_dh_table(broken):
    assert controller_record("ur5e", broken) is None


# --- the comparison --------------------------------------------------------------------------------
def _dh_flange(robot: str, calibration: ControllerCalibration, q: np.ndarray) -> np.ndarray:
    """T_base_flange = Π Rz(θi + qi)·Tz(di)·Tx(ai)·Rx(αi), multiplied out by hand."""
    spec = get_robot(robot)
    theta = calibration.delta_theta
    a = np.asarray(spec.dh.a) + calibration.delta_a
    d = np.asarray(spec.dh.d) + calibration.delta_d
    alpha = np.asarray(spec.dh.alpha) + calibration.delta_alpha
    T = np.eye(4)
    for i in range(6):
        c, s = np.cos(theta[i] + q[i]), np.sin(theta[i] + q[i])
        ca, sa = np.cos(alpha[i]), np.sin(alpha[i])
        T = T @ np.array([[c, -s * ca, s * sa, a[i] * c], [s, c * ca, -c * sa, a[i] * s],
                          [0.0, sa, ca, d[i]], [0.0, 0.0, 0.0, 1.0]])
    return T


@pytest.fixture(scope="module")
def data():
    rng = np.random.default_rng(14)
    truth = random_truth("ur5e", rng, rigid=True)  # the controller's model is the subject, not the sag
    q_fit, p_fit = measure(truth, visible_poses(truth, 30, rng), Noise(encoder_sigma=0.0), rng)
    q_val, p_val = measure(truth, visible_poses(truth, 15, rng), Noise(encoder_sigma=0.0), rng)
    smr_guess = truth.smr + 0.003
    fitted = Measurements.from_arrays(q_fit, p_fit, "fit")
    return truth, fitted, Measurements.from_arrays(q_val, p_val, "val"), smr_guess


def test_the_controller_figures_match_a_hand_computation(data):
    _truth, fitted, held_out, smr_guess = data
    stats = controller_validation(CALIBRATION, "ur5e", fitted, held_out, smr_guess)
    # the tracker pose and SMR offset fitted for the controller's arm, then its DH chain by hand
    located = register(fitted, "ur5e", smr_guess, arm=CALIBRATION.geometry("ur5e"))
    T_inv = np.linalg.inv(located.tracker.homogeneous)
    predicted = np.array([(T_inv @ _dh_flange("ur5e", CALIBRATION, q) @ np.r_[located.smr, 1.0])[:3]
                          for q in held_out.q])
    errors = np.linalg.norm(held_out.p - predicted, axis=1)
    assert stats.count == 15
    assert stats.mean == pytest.approx(errors.mean(), rel=1e-9)
    assert stats.rms == pytest.approx(np.sqrt(np.mean(errors**2)), rel=1e-9)
    assert stats.max == pytest.approx(errors.max(), rel=1e-9)
    # the registration is a genuine fit: better on the fitted points than the nominal arm's
    nominal = register(fitted, "ur5e", smr_guess)
    assert validate(located, fitted).rms != validate(nominal, fitted).rms


def test_what_the_tracker_cannot_see_is_not_charged_to_the_controller(data):
    """δd1 and δθ1 move the base frame, δθ6 turns the flange about its axis: a tracker cannot tell
    them from its own placement and the SMR offset, so the controller scores as the nominal arm — where
    hil's fitted tracker pose and SMR offset with the controller's arm swapped in would be millimetres off."""
    _truth, fitted, held_out, smr_guess = data
    frames_only = ControllerCalibration(delta_theta=[3e-3, 0, 0, 0, 0, 2e-3], delta_d=[2e-3, 0, 0, 0, 0, 0])
    theirs = controller_validation(frames_only, "ur5e", fitted, held_out, smr_guess)
    before = validate(register(fitted, "ur5e", smr_guess), held_out)
    assert theirs.rms == pytest.approx(before.rms, rel=1e-6, abs=1e-9)
    nominal = register(fitted, "ur5e", smr_guess)
    swapped = frames_only.geometry("ur5e", nominal.smr, nominal.tracker)
    assert validate(swapped, held_out).rms > before.rms + 1e-3


# --- in the plan and the runner --------------------------------------------------------------------
def _controller_is_the_truth(rng: np.random.Generator) -> Geometry:
    """A world whose arm is exactly the controller's model (plus a tracker and an SMR)."""
    placed = random_truth("ur5e", rng, ideal=True)
    return CALIBRATION.geometry("ur5e", placed.smr, placed.tracker)


def _config(truth: Geometry):
    return default_config().with_overrides(campaign__calibration_poses=12, campaign__validation_poses=8,
                                           robot__settle_time=0.0, smr__offset=tuple(truth.smr + 0.003),
                                           tracker__position=tuple(truth.tracker.translation + 0.05),
                                           warmup__enabled=False, drift__every=0)  # a dry run


def test_the_plan_validates_the_controllers_model_beside_hils():
    rng = np.random.default_rng(7)
    truth = _controller_is_the_truth(rng)
    record = controller_record("ur5e", fake_kinematics(CALIBRATION))
    events: list[Any] = []

    def choose(request: Any) -> Choice:
        return Choice(visible_poses(request.model, request.count, rng), {"method": "test"})

    def respond(step: Any) -> Any:
        if isinstance(step, Acquire):
            q = np.array(step.steps[0].q)
            q_read, points = measure(truth, q[None], Noise(encoder_sigma=0.0), rng)
            return PoseRecord(step.index, step.role, q, q_read[0], np.zeros(6), points[0], np.zeros(3), 1)
        if isinstance(step, Emit):
            events.append(step.event)
        return None

    _, result = dry_run(calibration_plan(_config(truth), choose, "c1", controller=record), respond)
    (done,) = [e for e in events if isinstance(e, ValidationDone)]
    assert done.controller == result.controller.as_dict() and result.controller.count == 8
    # the controller's model is the truth here: it scores like the tracker's noise, the nominal arm not
    assert result.controller.rms < 80e-6 < 3e-4 < result.before.rms
    assert result.model["controller"] == {k: record[k] for k in (
        "delta_theta", "delta_a", "delta_d", "delta_alpha", "checksum", "calibration_status")}
    identified = next(e for e in events if type(e).__name__ == "ModelIdentified")
    assert identified.model["controller"] == result.model["controller"]


def test_without_a_controller_model_nothing_changes():
    rng = np.random.default_rng(8)
    truth = random_truth("ur5e", rng, ideal=True)

    def respond(step: Any) -> Any:
        if isinstance(step, Acquire):
            q = np.array(step.steps[0].q)
            q_read, points = measure(truth, q[None], Noise(encoder_sigma=0.0), rng)
            return PoseRecord(step.index, step.role, q, q_read[0], np.zeros(6), points[0], np.zeros(3), 1)
        return None

    choose = lambda request: Choice(visible_poses(request.model, request.count, rng), {})  # noqa: E731
    _, result = dry_run(calibration_plan(_config(truth), choose, "c1"), respond)
    assert result.controller is None and "controller" not in result.model


class _Devices:
    def __init__(self, arm: FakeArm, tracker: FakeTracker) -> None:
        self.robot, self.tracker = arm, tracker

    def close(self) -> None:
        pass


def test_the_runner_keeps_the_controllers_model_and_the_result_reports_it():
    rng = np.random.default_rng(9)
    truth = _controller_is_the_truth(rng)
    arm = FakeArm(visible_poses(truth, 1, rng)[0], encoder_sigma=0.0)
    arm.info = SimpleNamespace(model="UR5e", serial="20235500042", software_version="5.15",
                               kinematics=fake_kinematics(CALIBRATION))
    events: list[Any] = []
    bus = EventBus()
    bus.subscribe(events.append, critical=True)
    config = _config(truth)

    def choose(request: Any) -> Choice:
        return Choice(visible_poses(request.model, request.count, rng), {"method": "test"})

    devices = _Devices(arm, FakeTracker(arm, truth))
    outcome = run_campaign(config, choose, bus=bus, campaign="c1", devices=devices)
    # the controller's model is the truth here: no calibration beats it, and the verdict says so
    assert outcome.status == "rejected", outcome.error
    assert "worse than the controller's own model" in outcome.result.verdict.reason or \
        "better than the controller's own model" in outcome.result.verdict.reason
    record = controller_record("ur5e", arm.info.kinematics)
    assert outcome.robot_info["controller"] == record
    names = [type(e) for e in events]
    assert names.index(ControllerModel) == names.index(RunStarted) + 1
    (kept,) = [e for e in events if isinstance(e, ControllerModel)]
    assert kept.model == record
    doc = result_document(outcome, config, events, 0.0, None)
    assert doc["validation"]["controller"] == pytest.approx(outcome.result.controller.as_dict())
    assert len(doc["per_pose"]["validation"]["controller"]) == len(doc["per_pose"]["validation"]["after"])
    assert doc["model"]["controller"]["checksum"] == CALIBRATION.checksums()
    assert doc["robot_info"]["controller"]["calibration_status"] == 2


def test_a_comparison_that_cannot_be_made_is_said_and_the_campaign_goes_on(monkeypatch):
    import hil.campaign.calibration_plan as plan_module
    from hil.calibration.identification import IdentificationError
    from hil.campaign.events import Message

    def fails(*args: Any, **kwargs: Any) -> Any:
        raise IdentificationError("the registration did not converge")

    monkeypatch.setattr(plan_module, "controller_validation", fails)
    rng = np.random.default_rng(7)
    truth = _controller_is_the_truth(rng)
    events: list[Any] = []

    def respond(step: Any) -> Any:
        if isinstance(step, Acquire):
            q = np.array(step.steps[0].q)
            q_read, points = measure(truth, q[None], Noise(encoder_sigma=0.0), rng)
            return PoseRecord(step.index, step.role, q, q_read[0], np.zeros(6), points[0], np.zeros(3), 1)
        if isinstance(step, Emit):
            events.append(step.event)
        return None

    choose = lambda request: Choice(visible_poses(request.model, request.count, rng), {})  # noqa: E731
    record = controller_record("ur5e", fake_kinematics(CALIBRATION))
    _, result = dry_run(calibration_plan(_config(truth), choose, "c1", controller=record), respond)
    assert result.controller is None and "controller" in result.model
    # the cross-validation still has the controller's model (the truth): the fit cannot beat it
    assert not result.passed and "controller's own model" in result.verdict.reason
    (warning,) = [e for e in events if isinstance(e, Message)]
    assert warning.level == "warning" and "did not converge" in warning.text
