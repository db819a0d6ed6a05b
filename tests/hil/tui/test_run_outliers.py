"""The Run screen's outlier marks on the realistic arm: the bootstrap's points (registered on
themselves, hundredths of a millimetre from nominal) do not make every calibration pose (millimetres
from nominal: the arm's plain error) an outlier (seen under tmux at 80x24, issue 29 c)."""

from __future__ import annotations

import asyncio

from hil.campaign.events import PointMeasured, PoseStarted, RunStarted
from hil.tui.messages import EngineEvent
from tests.hil.tui.conftest import screen_text, wait_for
from tests.hil.tui.test_snapshots import SIZE, T0, offline_app

CID = "20261127-161234-a1b8"


def point(index: int, role: str, deviation: float | None) -> PointMeasured:
    return PointMeasured(campaign=CID, t=T0 + index, index=index, role=role, q=[0.1] * 6, p=[2.5, 0.0, 0.4],
                         p_spread=[0.0] * 3, samples=5, deviation=deviation, target=[0.1] * 6)


def test_calibration_poses_millimetres_from_nominal_are_not_outliers_against_the_bootstrap():
    boot = [0.087e-3, 0.107e-3, 0.068e-3, 0.060e-3, 0.049e-3, 0.086e-3, 0.052e-3]  # as seen, sim seed 1
    cal = [2.583e-3, 0.883e-3, 3.159e-3, 1.379e-3, 2.052e-3, 0.898e-3]
    events = [RunStarted(campaign=CID, t=T0, robot="ur5e", station="sim", poses=50)]
    events += [point(i, "bootstrap", None if i < 3 else boot[i - 3]) for i in range(10)]
    events += [point(10 + k, "calibration", d) for k, d in enumerate(cal)]
    events.append(PoseStarted(campaign=CID, t=T0 + 20, index=16, role="calibration", target=[0.1] * 6))

    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            for event in events:
                app.post_message(EngineEvent(event))
            await pilot.press("3")
            await wait_for(pilot, lambda: "3.159" in screen_text(app), 5, "the calibration poses drawn")
            text = screen_text(app)
            assert "× median" not in text, text  # no outlier series in the plot's legend
            table = app.screen.query_one("#poses")
            styles = [str(cell.style) for row in range(table.row_count)
                      for cell in [table.get_cell_at((row, 3))]]
            assert not [s for s in styles if "red" in s], styles

    asyncio.run(scenario())
