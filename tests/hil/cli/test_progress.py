"""The terminal's progress lines word a calibration and a verification each in its own terms, from what
the events say (the plan's ``"kind": "verification"`` and each visit's pose, mode and cycle)."""

from __future__ import annotations

import io

from hil.campaign.events import (
    ControllerModel,
    PhaseChanged,
    PlanReady,
    PointMeasured,
    PoseSkipped,
    RunFinished,
    RunStarted,
)
from hil.cli.support.progress import VERIFICATION, Progress
from hil.verify.verification_plan import KIND

MODES = ["uncompensated", "compensated"]


def visits(cycles: int = 2) -> list[dict]:
    out = []
    for cycle in range(1, cycles + 1):
        for mode in MODES:
            for pose in ("P1", "P5", "P4", "P3", "P2"):
                out.append({"index": len(out) + 1, "role": "validation", "q": [0.0] * 6, "pose": pose,
                            "mode": mode, "cycle": cycle})
    return out


def point(index: int, deviation: float | None = 2.5e-5, role: str = "validation") -> PointMeasured:
    return PointMeasured(campaign="v", index=index, role=role, q=[0.0] * 6, p=[0.0] * 3, p_spread=[0.0] * 3,
                         samples=2, deviation=deviation)


def verification_events(resumed: bool = False) -> list:
    return [RunStarted(campaign="v", robot="ur5e", station="cell", poses=20, resumed=resumed,
                       measured=7 if resumed else 0),
            ControllerModel(campaign="v", model={}),
            PlanReady(campaign="v", poses=visits(), selection={"kind": KIND, "cycles": 2, "modes": MODES}),
            PhaseChanged(campaign="v", phase="measure", detail="20 of 20 visits to measure"),
            point(1), point(8, None),
            PoseSkipped(campaign="v", index=13, role="validation", reason="beam lost"),
            RunFinished(campaign="v", status="accepted", detail="ISO 9283 over 2 cycles (worst pose): …")]


def lines(events: list, bar: bool = False) -> str:
    stream = io.StringIO()
    progress = Progress(stream, bar=bar)
    for event in events:
        progress(event)
    return stream.getvalue()


def test_a_verification_says_visits_poses_modes_and_cycles():
    assert VERIFICATION == KIND  # the constant the CLI keeps to stay light is the plan's
    out = lines(verification_events()).splitlines()
    assert out == [
        "starting verification v on ur5e (cell), 20 visits planned (poses P1–P5, 2 cycles, uncompensated "
        "and compensated)",
        "measure: 20 of 20 visits to measure",
        "measured visit 1 (P1 uncompensated, cycle 1 of 2), 0.025 mm from commanded",
        "measured visit 8 (P4 compensated, cycle 1 of 2)",
        "skipped visit 13 (P4 uncompensated, cycle 2 of 2): beam lost",
        "verification v finished: ISO 9283 over 2 cycles (worst pose): …",
    ]
    resumed = lines(verification_events(resumed=True))
    assert resumed.startswith("resuming verification v on ur5e (cell), 20 visits planned") and \
        "compensated), 7 measured\n" in resumed


def test_the_bar_counts_visits_and_names_the_visit():
    out = lines(verification_events(), bar=True)
    assert "1/20 visits" in out and "P1 uncompensated, cycle 1 of 2, 0.025 mm from commanded" in out
    assert "poses" not in out.replace("poses P1–P5", "")


def test_a_calibration_is_worded_as_before():
    events = [RunStarted(campaign="c", robot="ur5e", station="cell", poses=4),
              PhaseChanged(campaign="c", phase="bootstrap", detail="locating the tracker"),
              point(0, None, "bootstrap"),
              PlanReady(campaign="c", poses=[{"index": i, "role": "calibration", "q": [0.0] * 6}
                                             for i in range(1, 5)], selection={"calibration": {}}),
              point(1, 1.2e-3, "calibration"),
              PoseSkipped(campaign="c", index=2, role="calibration", reason="x"),
              RunFinished(campaign="c", status="accepted", detail="validation RMS 0.02 mm")]
    assert lines(events).splitlines() == [
        "starting campaign c on ur5e (cell), 4 poses planned (calibration + validation)",
        "bootstrap: locating the tracker",
        "measured pose 0 (bootstrap)",
        "measured pose 1 (calibration), 1.200 mm from nominal",
        "skipped pose 2 (calibration): x",
        "campaign c accepted: validation RMS 0.02 mm",
    ]


def test_a_run_that_fails_before_its_plan_still_says_it_started():
    out = lines([RunStarted(campaign="v", robot="ur5e", station="cell", poses=20),
                 RunFinished(campaign="v", status="failed", detail="FaultError: no beam")])
    assert out.splitlines() == ["starting campaign v on ur5e (cell), 20 poses planned (calibration + "
                                "validation)", "campaign v failed: FaultError: no beam"]
