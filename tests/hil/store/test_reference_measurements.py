"""The store keeps a campaign's reference measurements (warm-up and drift watch) in its log: committed as
each is recorded, read back in order after the process is gone, never a campaign point; the warm-up and
drift settings do not change which campaign a re-run resumes."""

from __future__ import annotations

import numpy as np

from hil.campaign.events import (
    DriftFlagged,
    PlanReady,
    PointMeasured,
    ReferenceMeasured,
    WarmupFinished,
)
from hil.campaign.runner import plan_saver, resume_state
from hil.station.config import default_config
from hil.store import Store
from hil.store.hashing import measurement_hash

Q = [0.1, -1.2, 1.5, -1.9, -1.6, 0.3]


def reference(cid: str, seq: int, **kw) -> ReferenceMeasured:
    values = dict(run=1, phase="warmup", elapsed=120.0 * seq, q=Q, xyz=[2.0, 0.1 + 1e-6 * seq, 0.3],
                  p_spread=[1e-6] * 3, moved=1e-6 * seq, temperatures=[30.0 + seq] * 6)
    return ReferenceMeasured(campaign=cid, seq=seq, **{**values, **kw})


def test_reference_measurements_are_kept_in_the_log_and_read_back_after_a_restart(tmp_path):
    path = tmp_path / "hil.db"
    with Store.open(path) as store:
        cid = store.create_campaign(default_config(), "ur5e")
        save = plan_saver(store, cid)
        plan = PlanReady(campaign=cid, poses=[{"index": 0, "role": "calibration", "q": Q},
                                              {"index": 1, "role": "validation", "q": Q}],
                         tracker={"xyz": [2.5, 0.0, 0.3], "rpy": [0.0, 0.0, 3.14]}, reference=Q)
        store.record_event(plan)
        save(plan)
        sent = [reference(cid, 1), reference(cid, 2), reference(cid, 3, baseline=True, drift=0.0)]
        for event in sent:
            store.record_event(event)
        store.record_event(WarmupFinished(campaign=cid, seconds=360.0, converged=True, references=3))
        store.record_event(reference(cid, 4, phase="drift", drift=4e-6))
        store.record_event(DriftFlagged(campaign=cid, drift=4e-5, limit=3e-5, elapsed=900.0, seq=4))
    # a new process (the first one is gone, as after kill -9): every commit is there
    with Store.open(path) as store:
        got = store.events(cid, types=("ReferenceMeasured",))
        assert [e.seq for e in got] == [1, 2, 3, 4]
        assert got[:3] == sent  # every field, the temperatures included
        assert [e.name for e in store.events(cid, types=("DriftFlagged", "WarmupFinished"))] == [
            "WarmupFinished", "DriftFlagged"]
        # never a campaign point: no measurement row, no pose measured
        assert store.measurements(cid) == [] and store.measured_poses(cid) == {}
        state = resume_state(store, cid)
    assert np.allclose(state.reference, Q)  # the same reference pose for the resumed run
    assert [e.seq for e in state.references] == [1, 2, 3, 4]
    assert [e.baseline for e in state.references] == [False, False, True, False]


def test_a_resumed_plan_without_a_stored_reference_leaves_the_choice_to_the_plan(tmp_path):
    with Store.open(tmp_path / "hil.db") as store:
        cid = store.create_campaign(default_config(), "ur5e")
        plan = PlanReady(campaign=cid, poses=[{"index": 0, "role": "calibration", "q": Q}],
                         tracker={"xyz": [2.5, 0.0, 0.3], "rpy": [0.0, 0.0, 3.14]})  # an older hil's
        store.record_event(plan)
        plan_saver(store, cid)(plan)
        store.record_event(PointMeasured(campaign=cid, index=0, role="calibration", q=Q, p=[2.0, 0.0, 0.3],
                                         p_spread=[0.0] * 3, samples=2))
        state = resume_state(store, cid)
    assert state.reference is None and state.references == []
    assert list(state.records) == [("calibration", 0)]


def test_the_warm_up_and_drift_settings_do_not_change_which_campaign_is_resumed(tmp_path):
    base = default_config()
    other = base.with_overrides(warmup__enabled=False, warmup__interval=60.0, drift__every=0,
                                drift__limit=5e-5)
    assert measurement_hash(base.as_dict()) == measurement_hash(other.as_dict())
    # a configuration stored before the sections existed hashes the same too
    old = {k: v for k, v in base.as_dict().items() if k not in ("warmup", "drift")}
    assert measurement_hash(old) == measurement_hash(base.as_dict())
    with Store.open(tmp_path / "hil.db") as store:
        cid = store.create_campaign(base, {"type": "ur5e", "serial": "20235500001"})
        assert store.find_resumable(other, robot_serial="20235500001") == cid
