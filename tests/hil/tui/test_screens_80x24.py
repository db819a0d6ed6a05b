"""The Run and Plan screens at 80x24, from canned state: what the operator can read without scrolling,
what the Plan screen refuses before a run starts, the plots' scales, and one pose count everywhere."""

from __future__ import annotations

import asyncio
import io

import numpy as np
import pytest
from textual.app import App, ComposeResult

from hil.campaign.events import EventBus, PlanReady, PointMeasured, RunFinished, RunStarted
from hil.campaign.runner import plan_saver
from hil.cli.support.progress import Progress
from hil.station.config import default_config
from hil.store import Store
from hil.tui.app import create_app
from hil.tui.messages import EngineEvent, SelectionDone
from hil.tui.screens.run import outlier_level, row_cells
from hil.tui.state import PoseRow
from hil.tui.widgets.plot import PlotView, Series
from tests.hil.tui.conftest import settled_text
from tests.hil.tui.test_snapshots import SIZE, T0, offline_app, run_events

REPORT = {"index": "O1", "value": 3.7e-4, "percent_of_bound": 93.7, "method": "tabu", "seconds": 0.5,
          "travel_time": {"ordered": 9.0}, "candidates": {"found": 3000}, "count": 12, "parameters": 25,
          "poses": []}
POINTS = np.column_stack([np.linspace(-0.6, 0.6, 12), np.linspace(-0.5, 0.5, 12), np.linspace(0.2, 0.9, 12)])


def _selection(text: str) -> str:
    """The Plan screen's Selection panel, its wrapped lines joined."""
    parts = [line.split("││", 1)[1].rstrip().rstrip("│") for line in text.splitlines() if "││" in line]
    return " ".join(" ".join(parts).split())


def _table_lines(text: str) -> list[str]:
    lines = text.splitlines()
    start = next(k for k, line in enumerate(lines) if line.split()[:2] == ["#", "role"])
    return lines[start:start + 9]


# --- item 1: the Run table ------------------------------------------------------------------------
def test_run_table_shows_every_deviation_and_status_at_80_columns():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            for event in run_events():
                app.post_message(EngineEvent(event))
            await pilot.pause()
            await pilot.press("3")
            rows = _table_lines(await settled_text(pilot))
            assert "dev [mm]" in rows[0] and "status" in rows[0]
            for index, dev in ((3, "2.000"), (4, "2.333"), (5, "2.667")):
                assert any(r.split()[:1] == [str(index)] and dev in r and "measured" in r for r in rows)
            assert any(r.split()[:3] == ["6", "cal", "skipped"] for r in rows)
            assert any(r.split()[:3] == ["7", "cal", "moving"] for r in rows)

    asyncio.run(scenario())


def test_deviation_colours_follow_the_campaigns_own_spread_not_the_acceptance_threshold():
    """A deviation from nominal (2-4 mm on a healthy arm) is not an accuracy figure: no colour says
    it is within or above the acceptance threshold (0.1 mm on the validation RMS after calibration);
    only a point far outside the campaign's own deviations is marked."""
    def style(deviation: float, outlier: float | None) -> str:
        row = PoseRow(3, "calibration", [0.0] * 6, "measured", [0.0] * 6, [1.0, 0.0, 0.0], deviation)
        (dev,) = [c for c in row_cells(row, outlier) if c.plain == f"{1e3 * deviation:.3f}"]
        return str(dev.style)

    deviations = [2.1e-3, 3.4e-3, 2.8e-3, 3.9e-3, 2.5e-3, 12.0e-3]
    outlier = outlier_level(deviations)
    assert outlier is not None
    assert [style(d, outlier) for d in deviations[:-1]] == [""] * 5  # neither green nor yellow
    assert "red" in style(deviations[-1], outlier)
    assert style(0.05e-3, outlier) == ""  # a small one is not "within acceptance" either
    assert style(3.0e-3, None) == ""  # too few points for a spread: nothing is marked


# --- item 2: counts the selector and the fit refuse ---------------------------------------------------
def test_plan_refuses_too_few_calibration_poses_before_selecting_or_saving():
    async def scenario():
        app = offline_app()
        asked = []
        app.start_selection = asked.append
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("2")
            app.screen.query_one("#in-poses").value = "5"
            await pilot.press("s")
            await pilot.pause()
            assert asked == []
            text = await settled_text(pilot)
            assert "calibration poses: at least 10" in _selection(text)
            assert "27 parameters" in _selection(text)
            assert "--count" not in text
            await pilot.press("u")
            assert app.session.plan_overrides == {}
            app.screen.query_one("#in-poses").value = "10"
            await pilot.press("s")
            assert len(asked) == 1 and asked[0]["campaign.calibration_poses"] == 10

    asyncio.run(scenario())


def test_run_refuses_to_start_a_campaign_whose_counts_cannot_calibrate():
    async def scenario():
        app = offline_app()
        # (fewer poses than identify is refused with the configuration itself: campaign.calibration_poses)
        app.session.config = default_config().with_overrides(campaign__candidates=20)
        started = []
        app.action_start_run = lambda: started.append(True)
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("3")
            await pilot.press("g")
            await pilot.pause()
            assert started == []
            app.session.config = default_config()
            await pilot.press("g")
            await pilot.pause()
            assert started == [True]

    asyncio.run(scenario())


# --- item 3: is the preview what the run measures? -------------------------------------------------
@pytest.mark.parametrize("position, expected", [
    (None, "the run locates the tracker, then selects again"),
    ((3.0, 0.0, 0.5), "the poses the next run measures"),
])
def test_plan_says_whether_the_run_measures_the_previewed_poses(position, expected):
    async def scenario():
        app = offline_app()
        app.session.config = app.session.config.with_overrides(tracker__position=position)
        app.start_selection = lambda values: None
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("2")
            await pilot.press("s")
            where = position or (2.5, 0.0, 0.5)
            app.post_message(SelectionDone(REPORT, POINTS, where, position is None))
            assert expected in _selection(await settled_text(pilot))
            if position is not None:  # other settings for the next run: the preview is not its plan
                app.screen.query_one("#in-seed").value = "7"
                await pilot.press("u")
                assert "the next run has other settings" in _selection(await settled_text(pilot))

    asyncio.run(scenario())


# --- item 4: plots with scales and legends, fields that look like fields -------------------------------
class _PlotApp(App[None]):
    def __init__(self, **kwargs) -> None:
        super().__init__()
        self.kwargs = kwargs

    def compose(self) -> ComposeResult:
        yield PlotView(id="p", **self.kwargs)


def _plot(series, size, **kwargs) -> str:
    async def scenario():
        app = _PlotApp(**kwargs)
        async with app.run_test(size=size) as pilot:
            app.query_one(PlotView).plot(series)
            return await settled_text(pilot)

    return asyncio.run(scenario())


def _top_view(tracker):
    return [Series(POINTS[:, 0], POINTS[:, 1], marker="•", label="pose"),
            Series(np.zeros(1), np.zeros(1), marker="R", label="base"),
            Series(np.array([tracker[0]]), np.array([tracker[1]]), marker="T", label="tracker",
                   optional=True)]


def test_pose_plot_has_a_scale_and_a_legend_and_shows_the_tracker():
    text = _plot(_top_view((1.5, 0.0)), (38, 12), title="top view [m]", equal=True, x_label="x→",
                 y_label="y↑")
    lines = text.splitlines()
    assert "• pose" in lines[0] and "R base" in lines[0] and "T tracker" in lines[0]
    assert "0.0┤" in text and "y↑└" in lines[-1] and lines[-1].rstrip().endswith("x→")
    assert any(ch.isdigit() for ch in lines[-1])  # x tick labels
    assert "T" in "".join(lines[1:-1]) and "off plot" not in text


def test_a_tracker_far_off_the_poses_is_marked_off_the_plot_not_pinned_to_its_border():
    text = _plot(_top_view((6.0, 0.2)), (38, 12), title="top view [m]", equal=True, x_label="x→")
    assert "off plot T→" in text
    # the poses keep the scale: the x ticks stay within their metre or so
    assert "6" not in text.splitlines()[-1]


def test_deviation_plot_has_an_x_axis_of_points_and_a_y_scale():
    d = np.array([2.0, 2.3, 2.6, 2.1, 1.7, 2.9, 3.1])
    text = _plot([Series(np.arange(1, 8.0), d, line=True, label="deviation")], (78, 6),
                 title="deviation from nominal [mm]", y_floor=0.0, x_label="point", integer_x=True)
    lines = text.splitlines()
    assert "0┤" in text and "─ deviation" in lines[0]
    axis = lines[-1]
    assert axis.rstrip().endswith("point") and all(str(k) in axis for k in range(1, 8))


def test_a_focused_field_keeps_the_footer_keys_and_s_still_selects():
    async def scenario():
        app = offline_app()
        asked = []
        app.start_selection = asked.append
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("2")
            await pilot.press("tab")
            field = app.screen.query_one("#in-poses")
            assert app.screen.focused is field
            await pilot.press("1", "4")
            assert field.value == "14"  # digits go into the field (selected on focus: replaced)
            footer = (await settled_text(pilot)).splitlines()[-1]
            assert "s Select poses" in footer and "u Use for next run" in footer and "esc" in footer
            await pilot.press("s")
            assert len(asked) == 1 and asked[0]["campaign.calibration_poses"] == 14

    asyncio.run(scenario())


# --- item 5: one pose count everywhere ----------------------------------------------------------------
def test_one_pose_count_everywhere_after_a_resume(tmp_path):
    """3 bootstrap points, 4 planned poses (3 calibration, 1 validation), 2 measured before a kill: the
    store's history, the CLI's progress bar and the Run screen all count 4 poses, bootstrap apart."""
    plan = [{"index": 3 + k, "role": "calibration" if k < 3 else "validation", "q": [0.1 * k] * 6}
            for k in range(4)]

    def point(index: int, role: str, t: float) -> PointMeasured:
        return PointMeasured(campaign=cid, t=t, index=index, role=role, q=[0.1 * index] * 6, p=[1.0, 0, 0],
                             p_spread=[0.0] * 3, samples=5, deviation=None, target=[0.1 * index] * 6)

    with Store.open(tmp_path / "hil.db") as store:
        cid = store.create_campaign(default_config().as_dict(), {"type": "ur5e", "serial": "1"})
        bus = EventBus()
        bus.subscribe(store.as_subscriber(), critical=True)
        bus.subscribe(plan_saver(store, cid), critical=True)
        first = [RunStarted(campaign=cid, t=T0, robot="ur5e", station="s", poses=4),
                 *(point(k, "bootstrap", T0 + k) for k in range(3)),
                 PlanReady(campaign=cid, t=T0 + 4, poses=plan),
                 point(3, "calibration", T0 + 5), point(4, "calibration", T0 + 6)]
        for event in first:
            bus.emit(event)
        # the resumed run (what hil.campaign.runner emits: the plan's poses, measured ones among them)
        second = [RunStarted(campaign=cid, t=T0 + 100, robot="ur5e", station="s", poses=4, resumed=True,
                             measured=2),
                  PlanReady(campaign=cid, t=T0 + 101, poses=plan),
                  point(5, "calibration", T0 + 102), point(6, "validation", T0 + 103),
                  RunFinished(campaign=cid, t=T0 + 110, status="accepted", detail="")]
        stream = io.StringIO()
        progress = Progress(stream, bar=True)
        for event in second:
            bus.emit(event)
            progress(event)
        summary = store.campaign(cid).summary
    assert (summary.measured, summary.planned) == (4, 4)  # hil history's POSES column
    assert (progress.done, progress.total) == (4, 4)
    assert "4 poses planned" in stream.getvalue() and "4/4 poses" in stream.getvalue()

    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            for event in second:  # the app sees the resumed run
                app.post_message(EngineEvent(event))
            await pilot.pause()
            await pilot.press("3")
            status = next(line for line in (await settled_text(pilot)).splitlines() if cid in line)
            assert "4/4 poses" in status

    asyncio.run(scenario())


def test_run_status_shows_bootstrap_points_apart_from_the_poses():
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            cid = "c1"
            app.post_message(EngineEvent(RunStarted(campaign=cid, t=T0, robot="ur5e", station="s", poses=16)))
            for k in range(3):
                app.post_message(EngineEvent(PointMeasured(
                    campaign=cid, t=T0 + k, index=k, role="bootstrap", q=[0.0] * 6, p=[1.0, 0, 0],
                    p_spread=[0.0] * 3, samples=5, deviation=None, target=[0.0] * 6)))
            await pilot.pause()
            await pilot.press("3")
            status = next(line for line in (await settled_text(pilot)).splitlines() if cid in line)
            assert "0/16 poses (+3 bootstrap)" in status

    asyncio.run(scenario())


# --- item 6: a terminal below 80x24 -------------------------------------------------------------------
def test_a_terminal_below_80x24_says_so_instead_of_a_cut_screen():
    async def scenario():
        app = create_app(start_station=False, sim=True, now=lambda: T0)
        async with app.run_test(size=(70, 20)) as pilot:
            text = " ".join((await settled_text(pilot)).split())
            assert "This terminal is 70×20; hil needs at least 80×24" in text
            assert "1 Station" not in text
            await pilot.press("2")
            assert "hil needs at least 80×24" in " ".join((await settled_text(pilot)).split())
            await pilot.resize_terminal(80, 24)
            text = await settled_text(pilot)
            assert "hil needs" not in text and "1 Station" in text

    asyncio.run(scenario())


def test_a_state_change_before_a_screens_widgets_are_mounted_waits_for_its_mount():
    """A station event can reach a screen that is mounted while its widgets are not yet (a loaded
    machine): redrawing it then is a no-op, not a crash of the app; its own mount draws it."""
    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            await pilot.pause()
            station = app.views["station"]
            await station.query_one("#station-line").remove()  # as before its widgets are mounted
            with pytest.raises(Exception, match="station-line"):
                station.refresh_view()
            station.redraw()
            app._refresh()  # what a station event does
    asyncio.run(scenario())


# --- second round, items 8, 9, 12 and 13: the Run screen at 80x24 -------------------------------------
def _pose_events(count: int, target: list[float]) -> list:
    """A run of `count` calibration poses, all measured but the last, which is on its way."""
    from hil.campaign.events import PhaseChanged, PoseStarted, StateChanged

    cid = "20231114-221320-abcd"
    ev = [RunStarted(campaign=cid, t=T0, robot="ur5e", station="simulated station", poses=count),
          StateChanged(campaign=cid, t=T0, state="running", previous="idle"),
          PhaseChanged(campaign=cid, t=T0 + 1, phase="measure",
                       detail=f"{count} of {count} poses to measure")]
    for k in range(count):
        ev.append(PoseStarted(campaign=cid, t=T0 + 2 + k, index=k, role="calibration", target=target))
        if k < count - 1:
            ev.append(PointMeasured(campaign=cid, t=T0 + 2.5 + k, index=k, role="calibration",
                                    q=target, p=[-1.2345, 2.3456, 0.1234], p_spread=[0] * 3, samples=5,
                                    deviation=3.5e-3, target=target))
    return ev


async def _run_screen(events):
    app = offline_app()
    pilot_cm = app.run_test(size=SIZE)
    pilot = await pilot_cm.__aenter__()
    for event in events:
        app.post_message(EngineEvent(event))
    await pilot.pause()
    await pilot.press("3")
    await pilot.pause()
    await pilot.pause()
    return app, pilot, pilot_cm


def test_run_screen_shows_every_number_of_the_current_pose_uncut():
    target = [np.radians(v) for v in (-164.2, -117.5, 107.0, -35.4, 90.0, 175.3)]

    async def scenario():
        _, pilot, cm = await _run_screen(_pose_events(9, target))
        try:
            text = await settled_text(pilot)
            for value in ("-164.2", "-117.5", "107.0", "-35.4", "90.0", "175.3"):
                assert value in text, text  # the target of the pose under the cursor, whole
            measured = [line for line in text.splitlines() if "measured" in line and "cal" in line]
            assert measured and all("-1234.5 2345.6 123.4" in line for line in measured), text
            assert all(len(line) <= 80 for line in text.splitlines())
        finally:
            await cm.__aexit__(None, None, None)

    asyncio.run(scenario())


def test_run_table_is_whole_before_the_table_falls_idle():
    """The columns hold their longest text from the first frame. Sized automatically, they took their
    width when the table's queue fell idle; under a flood of engine events on a loaded machine the
    operator saw "measur" under "status" until then. Drawn here with the table's idle handler kept
    from running, as that flood kept it."""
    from textual.widgets import DataTable

    from hil.tui.screens.run import COLUMNS

    target = [np.radians(v) for v in (-164.2, -117.5, 107.0, -35.4, 90.0, 175.3)]

    async def scenario():
        app = offline_app()
        async with app.run_test(size=SIZE) as pilot:
            await pilot.press("3")
            await pilot.pause()
            table = app.screen.query_one("#poses", DataTable)

            async def never_idle(_event):  # the flood: the table's queue is never empty
                return None

            table._on_idle = never_idle
            for event in _pose_events(9, target):
                app.post_message(EngineEvent(event))
            await pilot.pause()
            widths = {str(key.value): column.get_render_width(table) - 2 * table.cell_padding
                      for key, column in table.columns.items()}
            assert widths["status"] >= len("measuring") and widths["p"] >= len("-1234.5 2345.6 123.4")
            far = _pose_events(2, target)[:-1]
            far.append(PointMeasured(campaign=far[0].campaign, t=T0 + 9, index=1, role="calibration",
                                     q=target, p=[-123.4567, 2.3456, 0.1234], p_spread=[0] * 3,
                                     samples=5, deviation=3.5e-3, target=target))
            for event in far:  # a point beyond the widths' 40 m: its column widens, nothing is cut
                app.post_message(EngineEvent(event))
            await pilot.pause()
            column = table.columns[next(k for k in table.columns if k.value == COLUMNS[-1][1])]
            assert column.width >= len("-123456.7 2345.6 123.4")

    asyncio.run(scenario())


def test_run_screen_lines_are_whole_and_indented_and_the_deviation_plot_has_no_acceptance_line():
    from hil.campaign.events import PhaseChanged, WarmupProgress

    cid = "20231114-221320-abcd"
    events = [*_pose_events(3, [0.1] * 6),
              PhaseChanged(campaign=cid, t=T0 + 20, phase="warmup",
                           detail="cycling 14 calibration poses; the reference pose is measured every "
                                  "120 s until the arm is warm")]
    events.append(WarmupProgress(campaign=cid, t=T0 + 30, elapsed=300.0, moved=7.6e-6, interval=134.0,
                                 limit=10e-6, max_time=3600.0))

    async def scenario():
        _, pilot, cm = await _run_screen(events)
        try:
            text = await settled_text(pilot)
            lines = text.splitlines()
            assert all(not line or line.startswith(" ") for line in lines), text  # nothing at column 0
            joined = " ".join(" ".join(lines).split())
            assert "measured every 120 s until the arm is warm" in joined, text
            assert "acceptance" not in text  # the deviation from nominal is not what acceptance judges
        finally:
            await cm.__aexit__(None, None, None)

    asyncio.run(scenario())


def test_a_suspended_pose_stays_in_view():
    from hil.campaign.events import StateChanged, Suspended

    cid = "20231114-221320-abcd"
    events = [*_pose_events(33, [0.1] * 6),
              StateChanged(campaign=cid, t=T0 + 50, state="suspended", previous="running"),
              Suspended(campaign=cid, t=T0 + 50, kind="beam_lost",
                        message="clear the line of sight between the tracker and the SMR; the run resumes "
                                "by itself", timeout=60.0, on_timeout="skip")]

    async def scenario():
        _, pilot, cm = await _run_screen(events)
        try:
            text = await settled_text(pilot)
            rows = [line.split() for line in text.splitlines()]
            assert ["32", "cal", "moving"] in [r[:3] for r in rows], text
        finally:
            await cm.__aexit__(None, None, None)

    asyncio.run(scenario())


def test_the_step_line_counts_the_poses_measured_so_far_not_the_phase_start():
    from hil.campaign.events import StateChanged

    cid = "20231114-221320-abcd"
    events = [*_pose_events(6, [0.1] * 6)[:-1],  # pose 5 started, then:
              StateChanged(campaign=cid, t=T0 + 40, state="paused", previous="running"),
              StateChanged(campaign=cid, t=T0 + 41, state="running", previous="paused")]
    events = [e for e in events if getattr(e, "index", None) != 5]  # all started poses measured

    async def scenario():
        _, pilot, cm = await _run_screen(events)
        try:
            text = await settled_text(pilot)
            assert "6 of 6 poses to measure" not in text, text
            assert "5 of 6" in text, text
        finally:
            await cm.__aexit__(None, None, None)

    asyncio.run(scenario())
