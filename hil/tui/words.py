"""What went wrong, in the operator's words: the drivers' typed errors as plain sentences.

Every screen, banner and notice of the app says a fault with `plain` — never an exception's class
name or a protocol's command name (``TargetLost: MOT_ReadLockStatus …``). The technical text stays in
the log (`technical`) and in the stored events (`hil.store`).
"""

from __future__ import annotations

from drivers.robot import errors as robot_errors
from drivers.tracker import errors as tracker_errors
from hil.errors import InputError

#: What to do after an emergency stop, in order (Station and Run screens).
ESTOP_STEPS: tuple[str, ...] = (
    "release the emergency stop button (twist it out)",
    "power the arm on (teach pendant)",
    "release the brakes (teach pendant)",
    "reconnect: c on the Station screen",
    "resume the campaign: g on the Run screen",
)

_SUSPENSIONS = {  # Suspended.kind -> headline
    "beam_lost": "beam lost",
    "unstable_point": "unstable reading",
    "tracker_link": "tracker link",
    "tracker_unplugged": "tracker unplugged",
    "tracker_not_ready": "tracker not ready",
    "protective_stop": "protective stop",
    "connection_lost": "robot link lost",
}


def kind_words(kind: str) -> str:
    """A suspension's kind (``beam_lost``) as a headline ("beam lost")."""
    return _SUSPENSIONS.get(kind, kind.replace("_", " "))


def technical(exc: BaseException) -> str:
    """The error as a developer reads it (class and text): for the log, not for the screen."""
    return f"{type(exc).__name__}: {exc}"


def plain(exc: BaseException) -> str:
    """The error as the operator reads it: what happened, and where it helps, what to do."""
    from hil.campaign.engine import SuspendTimeout
    from hil.store import StoreError

    text = str(exc).strip()
    if isinstance(exc, robot_errors.EmergencyStop):
        return "emergency stop: the arm is stopped and powered off"
    if isinstance(exc, robot_errors.ProtectiveStop):
        return "protective stop: clear its cause and unlock it on the teach pendant"
    if isinstance(exc, robot_errors.NotInRemoteControl):
        return "the teach pendant is in local control: switch it to remote control"
    if isinstance(exc, robot_errors.RobotNotReady):
        return f"the robot is not ready ({text})" if text else "the robot is not ready"
    if isinstance(exc, robot_errors.RobotUnreachable):
        return "the robot controller does not answer: check that it is on and its network cable"
    if isinstance(exc, robot_errors.ConnectionLost):
        return "lost the link to the robot controller: check the network; reconnect with c"
    if isinstance(exc, robot_errors.ProgramStopped):
        return "the program on the robot controller stopped (teach pendant?); reconnect with c"
    if isinstance(exc, robot_errors.SpeedSliderReduced):
        return f"the speed slider on the teach pendant is below 100 % ({text})"
    if isinstance(exc, robot_errors.TargetRejected):
        return f"the robot refused a target ({text})"
    if isinstance(exc, robot_errors.MotionTimeout):
        return "the arm did not reach its target in time; it was stopped"
    if isinstance(exc, robot_errors.MotionAborted):
        return "the motion was stopped"
    if isinstance(exc, robot_errors.RobotError):
        return f"robot: {text}" if text else "the robot reported a fault"
    if isinstance(exc, tracker_errors.TargetLost):
        return "the tracker lost the SMR: clear the line of sight between the tracker and the SMR"
    if isinstance(exc, tracker_errors.ConnectionLost):
        return "the link to the tracker is gone: check its cable or network"
    if isinstance(exc, tracker_errors.LinkError):
        return "the tracker's reply was garbled or late"
    if isinstance(exc, tracker_errors.NotReady):
        return "the tracker is not ready to measure (laser warming up or not initialized)"
    if isinstance(exc, tracker_errors.UnstablePoint):
        return "the SMR reading was not stable (vibration or air turbulence?)"
    if isinstance(exc, tracker_errors.TrackerError):
        return "the tracker refused the command"
    if isinstance(exc, SuspendTimeout) and exc.kind:
        return f"{kind_words(exc.kind)} for {exc.limit:.0f} s, the run stopped: {exc.instruction}"
    if isinstance(exc, StoreError):
        return f"the campaign database failed ({text})"
    if isinstance(exc, InputError | TimeoutError) and text:
        return text  # already one line naming the file, the field or the wait
    if isinstance(exc, OSError):
        where = f": {exc.filename}" if exc.filename else ""
        return f"{exc.strerror or text or 'input/output error'}{where}"
    return text or "an unexpected error (details in the log)"


def progress_words(measured: int, planned: int, bootstrap: int = 0) -> str:
    """How far an unfinished campaign got, as its stored summary says (``hil show``'s count): the
    campaign's poses once they are chosen, and the bootstrap's points apart — a campaign left during
    its bootstrap or its pose selection has no poses planned yet but keeps the points it measured,
    which "0 of ? poses measured" hid."""
    boot = f"{bootstrap} bootstrap point{'s' if bootstrap != 1 else ''}"
    if planned:
        return f"{measured} of {planned} poses measured" + (f" (+ {boot})" if bootstrap else "")
    if bootstrap:
        return f"{boot} measured, poses not chosen yet"
    return "nothing measured yet"


def shorten_middle(text: str, width: int) -> str:
    """`text` in at most `width` characters, cut from the middle ("20261127-1612…a1b8-model.json"): a
    file name keeps its start (the campaign's date) and its end (the kind of file), where a cut at the
    end would drop exactly what tells two files apart. Shown in full elsewhere (the caller's job)."""
    if len(text) <= width:
        return text
    if width < 3:
        return text[:width]
    head = width // 2
    tail = width - 1 - head
    return f"{text[:head]}…{text[len(text) - tail:]}" if tail else f"{text[:head]}…"
