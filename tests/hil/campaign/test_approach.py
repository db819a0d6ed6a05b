"""Every calibration and validation pose is approached from below in every joint, so each joint's lost
motion lags the same way at every pose measured (hil.campaign.steps.APPROACH, hil.arm.routes)."""

from __future__ import annotations

import numpy as np

from hil.arm.catalog import get_robot
from hil.arm.routes import Router
from hil.campaign.events import PoseReached, PoseStarted
from tests.hil.campaign.test_engine import Station


def test_every_measured_pose_is_reached_with_every_joint_moving_up() -> None:
    st = Station()
    st.config = st.config.with_overrides(campaign__approach=0.005)
    st.engine.run(st.plan())
    targets = st.arm.targets
    reached = st.of(PoseReached)
    assert reached
    aimed = {e.index: np.asarray(e.target) for e in st.of(PoseStarted)}
    for event in reached:
        q = aimed[event.index]
        i = max(k for k, t in enumerate(targets) if np.allclose(t, q, atol=1e-12))
        assert i > 0
        came_from = targets[i - 1]
        assert np.all(q - came_from >= 0.005 - 1e-12), (q - came_from)
    # the approach legs are the only extra moves: at most one a pose
    assert len(targets) <= 2 * len(reached) + 1


def test_the_router_adds_the_lead_in_only_where_it_is_needed_and_safe() -> None:
    spec = get_robot("ur5e")
    q = np.array([0.3, -1.3, 1.2, -1.5, -1.6, 0.1])
    router = Router(spec)
    assert [r.tolist() for r in router.route(q + 0.2, q, 0.005)] == [(q - 0.005).tolist(), q.tolist()]
    assert len(router.route(q - 0.2, q, 0.005)) == 1  # every joint already comes up far enough
    assert len(router.route(q + 0.2, q, 0.0)) == 1  # no approach asked
    # a lead-in beyond a joint limit is not taken: the pose is approached from where the arm comes
    at_limit = q.copy()
    at_limit[0] = spec.lower[0] + 0.001
    assert [r.tolist() for r in router.route(at_limit + 0.2, at_limit, 0.005)] == [at_limit.tolist()]
