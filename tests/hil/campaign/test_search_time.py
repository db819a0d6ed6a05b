"""``campaign.search_time``: the time-aware chooser improves its tour for as long as the station says,
and a longer search is at least as fast a tour (the search only keeps improvements)."""

from __future__ import annotations

from hil.campaign.calibration_plan import CALIBRATION, VALIDATION, SelectionRequest
from hil.campaign.chooser import campaign_chooser
from hil.station.config import EXAMPLE, load_config
from tests.hil.campaign.test_clustered_validation import CANDIDATES, _request


def test_the_search_runs_for_the_configured_time_and_a_longer_one_finds_no_slower_tour() -> None:
    tours = {}
    for seconds in (0.3, 3.0):
        config = load_config(EXAMPLE).with_overrides(
            campaign__selection="time-aware", campaign__candidates=CANDIDATES,
            campaign__search_time=seconds, campaign__calibration_poses=14, campaign__validation_poses=6)
        choose = campaign_chooser(config)
        val = choose(_request(config, seed=2))
        assert val.info["method"] == "random"
        base = _request(config, seed=1)
        cal = choose(SelectionRequest(CALIBRATION, 14, model=base.model, keep_in=base.keep_in,
                                      acceptance_angle=base.acceptance_angle, index=base.index,
                                      candidates=base.candidates, seed=1, exclude=val.poses,
                                      start=val.poses[0], fixed=val.poses))
        assert base.role == VALIDATION and cal.info["method"] == "time-aware"
        tours[seconds] = cal.info
    short, long = tours[0.3], tours[3.0]
    for seconds, info in tours.items():  # the tabu reference comes first; then the search runs its time
        assert info["seconds"] - info["seed_method"]["seconds"] >= seconds
    assert short["details"]["iterations"] <= long["details"]["iterations"]
    assert long["predicted"]["robot_time"] <= short["predicted"]["robot_time"] + 1e-9
    assert long["predicted"]["relative_error"] <= 1.0 + 1e-9  # still method 000's accuracy
