"""hil: hardware-in-the-loop kinematic calibration of Universal Robots arms.

One package per concern, each importing only those below it (checked by tests/test_layout.py):

    cli, tui          the command line and the operator's terminal app (on top)
    moveb             error-bounded smooth tool paths (seed 001): plan, time, run, measure
    report            the HTML report and the hil-result/1 document of a campaign
    store             the durable history (SQLite): campaigns, points, models, events
    campaign          plans, the engine, suspenders, events, the runner
    station           station.toml, the devices it names, the simulated station
    calibration       measurements, identification, model files, exports, synthetic truths, selection glue
    arm               robot catalog, geometry, kinematics, IK, safe targets
    files, errors     reading users' files, writing outputs atomically; the error types

`selector` (pose selection) and `drivers` (hardware) are separate packages that know nothing of hil.
"""


def __getattr__(name: str) -> str:
    """`hil.__version__`, looked up on first use (importlib.metadata costs a command's start-up time)."""
    if name != "__version__":
        raise AttributeError(f"module 'hil' has no attribute {name!r}")
    from importlib.metadata import PackageNotFoundError, version

    try:
        value = version("hil")
    except PackageNotFoundError:  # running from a source checkout that is not installed
        value = "0.1.0+src"
    globals()["__version__"] = value
    return value
