"""What the controller runs when ur_rtde uploads its control script, re-implemented natively.

The real client sends a URScript program (``def rtde_control(): ... end``) to port 30003 and then
drives it through RTDE registers: input int register 0 holds a command id, input double registers hold
its arguments, output int register 0 is the handshake (1 = ready, 2 = done with the command) and output
int register 2 reports async progress. `ControlScript` reproduces the behaviour of that program's main
loop and of the commands the product and its users need; it does not interpret URScript. Commands it
does not model are acknowledged without effect, like unknown ids in the real script.

Also here: the parser that recognises an uploaded program, and a tiny interpreter for the short custom
scripts ``sendCustomScriptFunction`` produces (movej/movel/register writes/sleep).
"""

from __future__ import annotations

import ast
import logging
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from mocks.ur.kin import matrix_to_pose, nearest_equivalent, pose_to_matrix, solve_ik
from mocks.ur.motion import MotionError, ServoTracker, SpeedTracker

if TYPE_CHECKING:
    from mocks.ur.arm import SimArm

log = logging.getLogger(__name__)

READY, DONE = 1, 2
# commands the real script processes every cycle without the ready/done handshake
REALTIME = frozenset({24, 11, 9, 10, 6, 25, 26, 27, 38, 58, 66, 67, 68, 69, 70, 71})
STOP_SCRIPT = 255


@dataclass
class PathMove:
    """One `movej(...)`/`movel(p...)` line injected by ``moveJ(path)``/``moveL(path)``."""

    kind: str  # "j" or "l"
    target: list[float]
    a: float
    v: float


@dataclass
class ParsedProgram:
    """What the script port understood of an uploaded program."""

    name: str
    reg_offset: int = 0
    path: list[PathMove] = field(default_factory=list)
    body: list[str] = field(default_factory=list)


_MOVE_RE = re.compile(
    r"^\s*move([jl])\((p?)\[([^\]]*)\]\s*,\s*a\s*=\s*([-+0-9.eE]+)\s*,\s*v\s*=\s*([-+0-9.eE]+)"
)


def parse_program(text: str) -> ParsedProgram | None:
    """Recognise a complete ``def name(): ... end`` program; None when it is not one."""
    lines = text.splitlines()
    if not lines:
        return None
    m = re.match(r"^def\s+(\w+)\s*\(\s*\)\s*:", lines[0].strip())
    if not m:
        return None
    prog = ParsedProgram(name=m.group(1))
    if prog.name == "rtde_control":
        off = re.search(r"global reg_offset_int = # int register offset\n\s*(\d+)", text)
        if off is None:
            off = re.search(r"global reg_offset_int\s*=\s*(\d+)", text)
        prog.reg_offset = int(off.group(1)) if off else 0
        marker = text.find("# inject move path\n")
        if marker >= 0:
            for line in text[marker:].splitlines()[1:]:
                if line.strip() == "end" or line.strip().startswith("def "):
                    break
                mm = _MOVE_RE.match(line)
                if mm:
                    target = [float(x) for x in mm.group(3).split(",")]
                    prog.path.append(PathMove("j" if mm.group(1) == "j" else "l", target,
                                              float(mm.group(4)), float(mm.group(5))))
    else:
        prog.body = [ln.strip() for ln in lines[1:-1] if ln.strip() and not ln.strip().startswith("#")]
    return prog


class ControlScript:
    """The ur_rtde control script's main loop and command set, executed natively each cycle."""

    def __init__(self, parsed: ParsedProgram) -> None:
        self.name = parsed.name
        self.off = parsed.reg_offset
        self.path = parsed.path
        self.executing = False
        self.blocking: Callable[[], bool] | None = None
        self.async_motion: Any = None
        self.async_wr_count = 0
        self.async_op_id = 0
        self.async_runner: _PathRunner | None = None
        self.arm: SimArm | None = None
        self.started = False

    # -- register helpers (with the script's register offset)
    def _ri(self, i: int) -> int:
        assert self.arm is not None
        return self.arm.in_int[i + self.off]

    def _rd(self, i: int) -> float:
        assert self.arm is not None
        return self.arm.in_double[i + self.off]

    def _vec(self, i: int) -> np.ndarray:
        return np.array([self._rd(i + k) for k in range(6)])

    def _wi(self, i: int, v: int) -> None:
        assert self.arm is not None
        self.arm.out_int[i + self.off] = int(v)

    def _wd6(self, v: np.ndarray) -> None:
        assert self.arm is not None
        for k in range(6):
            self.arm.out_double[k + self.off] = float(v[k])

    def _progress(self, value: int) -> None:
        """The script's async progress register (bits: op id, write count, running, progress)."""
        self.async_wr_count = (self.async_wr_count + 1) % 128
        if value == 0:
            self.async_op_id = (self.async_op_id + 1) % 128
        reg = self.async_wr_count * 65536 + self.async_op_id * 16777216
        if value >= 0:
            reg += min(value, 32767) + 32768
        self._wi(2, reg)

    # -- the main loop, one `sync()` per call
    def tick(self, arm: SimArm, now: float) -> bool:
        self.arm = arm
        if not self.started:
            self.started = True
            self._progress(-1)
            self._wi(0, READY)
            return True
        if self.async_motion is not None and arm.motion is not self.async_motion:
            self.async_motion = None
            self._progress(-1)
        if self.async_runner is not None and self.async_runner.advance():
            self.async_runner = None
            self._progress(-1)
        if self.blocking is not None:
            if not self.blocking():
                return True
            self.blocking = None
            self._wi(0, DONE)
            return True
        cmd = self._ri(0)
        if cmd in REALTIME:
            self._process(cmd)
            self._wi(0, READY)
        elif cmd == 0:
            self.executing = False
            self._wi(0, READY)
        elif not self.executing:
            self.executing = True
            if cmd == STOP_SCRIPT:
                return False
            self._process(cmd)
            if self.blocking is None:
                self._wi(0, DONE)
        return True

    # -- commands
    def _wait_motion(self, motion: Any) -> None:
        arm = self.arm
        assert arm is not None
        if motion is None:
            return
        self.blocking = lambda: arm.motion is not motion

    def _move(self, start: Callable[[], Any], is_async: bool) -> None:
        self._stop_async_move()
        motion = start()
        if is_async:
            if motion is not None:
                self.async_motion = motion
                self._progress(0)
        else:
            self._wait_motion(motion)

    def _stop_async_move(self) -> None:
        if self.async_motion is not None or self.async_runner is not None:
            self.async_motion = None
            self.async_runner = None
            self._progress(-1)

    def _ik(self, pose: np.ndarray, qnear: np.ndarray | None = None) -> np.ndarray:
        arm = self.arm
        assert arm is not None
        seed = arm.q if qnear is None else qnear
        q = solve_ik(arm.fk_tcp, pose_to_matrix(pose), seed)
        if q is None:
            raise MotionError("get_inverse_kin: no solution")
        return nearest_equivalent(q, seed)

    def _servo(self, q: np.ndarray) -> None:
        arm = self.arm
        assert arm is not None
        lookahead, gain = self._rd(9), self._rd(10)
        if isinstance(arm.motion, ServoTracker):
            arm.motion.target = q
            arm.motion.set_params(lookahead, gain)
        else:
            self._stop_async_move()
            arm.motion = ServoTracker(q, lookahead, gain, arm.config.max_speed)
        arm.q_target = q.copy()

    def _process(self, cmd: int) -> None:
        arm = self.arm
        assert arm is not None
        if cmd == 1:  # movej
            q, v, a, asy = self._vec(0), self._rd(6), self._rd(7), self._ri(1) == 1
            self._move(lambda: arm.start_movej(q, v, a), asy)
        elif cmd == 2:  # movej_ik
            q = self._ik(self._vec(0))
            v, a, asy = self._rd(6), self._rd(7), self._ri(1) == 1
            self._move(lambda: arm.start_movej(q, v, a), asy)
        elif cmd == 3:  # movel
            T = pose_to_matrix(self._vec(0))
            v, a, asy = self._rd(6), self._rd(7), self._ri(1) == 1
            self._move(lambda: arm.start_movel(T, v, a), asy)
        elif cmd == 4:  # movel_fk
            T = arm.fk_tcp(self._vec(0))
            v, a, asy = self._rd(6), self._rd(7), self._ri(1) == 1
            self._move(lambda: arm.start_movel(T, v, a), asy)
        elif cmd == 7:  # force_mode_stop
            self._wait_motion(arm.start_stop(10.0))
        elif cmd == 9:  # speedj
            qd, a = self._vec(0), self._rd(6)
            if isinstance(arm.motion, SpeedTracker):
                arm.motion.qd_target = np.clip(qd, -arm.config.max_speed, arm.config.max_speed)
                arm.motion.a = a if a > 0 else 0.5
            else:
                self._stop_async_move()
                arm.motion = SpeedTracker(arm.qd, qd, a, arm.config.max_speed)
        elif cmd == 11:  # servoj
            self._servo(self._vec(0))
        elif cmd == 24:  # servol
            self._servo(self._ik(self._vec(0)))
        elif cmd in (15, 16, 42):  # speed_stop, servo_stop, jog_stop
            a = self._rd(0) if cmd != 42 else 1.2
            self._wait_motion(arm.start_stop(a if a > 0 else 10.0))
        elif cmd in (33, 34):  # stopl / stopj
            a, asy = self._rd(0), self._ri(1) == 1
            self._stop_async_move()
            motion = arm.start_stop(a)
            if asy:
                self.async_motion = motion
                self._progress(0)
            else:
                self._wait_motion(motion)
        elif cmd == 26:  # get_steptime
            arm.out_double[self.off] = 1.0 / arm.config.rate_hz
        elif cmd == 27:  # get_actual_joint_positions_history (current sample)
            self._wd6(arm.actual_q)
        elif cmd == 28:  # get_target_waypoint
            self._wd6(matrix_to_pose(arm.fk_tcp(arm.q_target)))
        elif cmd == 29:  # set_tcp
            arm.tcp = self._vec(0)
        elif cmd in (30, 46):  # get_inverse_kin (with / without qnear)
            qnear = self._vec(6) if cmd == 30 else None
            self._wd6(self._ik(self._vec(0), qnear))
        elif cmd == 31:  # protective_stop
            arm.protective_stop("triggered by the program")
        elif cmd in (36, 37):  # is_within_safety_limits (pose / joints)
            if cmd == 37:
                ok = arm._within_limits(self._vec(0))
            else:
                try:
                    ok = arm._within_limits(self._ik(self._vec(0)))
                except MotionError:
                    ok = False
            self._wi(1, 1 if ok else 0)
        elif cmd == 38:  # get_joint_torques
            self._wd6(np.zeros(6))
        elif cmd == 39:  # pose_trans
            T = pose_to_matrix(self._vec(0)) @ pose_to_matrix(self._vec(6))
            self._wd6(matrix_to_pose(T))
        elif cmd == 40:  # get_tcp_offset
            self._wd6(arm.tcp)
        elif cmd == 43:  # get_forward_kin at the actual joints and active TCP
            self._wd6(matrix_to_pose(arm.fk_tcp(arm.actual_q)))
        elif cmd == 44:  # get_forward_kin(q, tcp)
            self._wd6(matrix_to_pose(arm.fk_tcp(self._vec(0), self._vec(6))))
        elif cmd == 45:  # move_path (the injected movej/movel lines)
            self._run_path(self._ri(1) == 1)
        elif cmd == 47:  # is_steady
            self._wi(1, 1 if arm.is_steady() else 0)
        elif cmd == 58:  # get_actual_tool_flange_pose
            self._wd6(matrix_to_pose(arm.fk_flange(arm.actual_q)))
        else:
            log.debug("control script: command %d acknowledged without effect", cmd)

    def _run_path(self, is_async: bool) -> None:
        arm = self.arm
        assert arm is not None
        self._stop_async_move()
        runner = _PathRunner(self, arm, list(self.path))
        if is_async:
            self._progress(0)
            self.async_runner = runner
            if runner.advance():
                self.async_runner = None
                self._progress(-1)
        else:
            self.blocking = runner.advance
            if runner.advance():
                self.blocking = None


class _PathRunner:
    """Runs the injected path one waypoint after the other, reporting progress like the script."""

    def __init__(self, script: ControlScript, arm: SimArm, steps: list[PathMove]) -> None:
        self.script, self.arm, self.steps = script, arm, steps
        self.i = -1
        self.motion: Any = None

    def advance(self) -> bool:
        """Start the next waypoint when the current one is finished; True when the path is done."""
        arm = self.arm
        if self.motion is not None and arm.motion is self.motion:
            return False
        self.i += 1
        if self.i >= len(self.steps):
            return True
        self.script._progress(self.i)
        st = self.steps[self.i]
        if st.kind == "j":
            self.motion = arm.start_movej(np.array(st.target), st.v, st.a)
        else:
            self.motion = arm.start_movel(pose_to_matrix(np.array(st.target)), st.v, st.a)
        return self.motion is None


_CALL_RE = re.compile(r"^(\w+)\((.*)\)$")


class CustomProgram:
    """A small custom script: sequential movej/movel/sleep/register writes; anything else is an error."""

    def __init__(self, parsed: ParsedProgram) -> None:
        self.name = parsed.name
        self.lines = parsed.body
        self.i = 0
        self.wait: Callable[[], bool] | None = None

    def tick(self, arm: SimArm, now: float) -> bool:
        while True:
            if self.wait is not None:
                if not self.wait():
                    return True
                self.wait = None
            if self.i >= len(self.lines):
                return False
            line = self.lines[self.i]
            self.i += 1
            if not self._exec(arm, line, now):
                return False

    def _exec(self, arm: SimArm, line: str, now: float) -> bool:
        m = _CALL_RE.match(line)
        if not m:
            arm.program_error(f"{self.name}: cannot execute {line!r}")
            return False
        fn, args_src = m.group(1), m.group(2)
        try:
            args, kwargs = _parse_args(args_src)
        except (ValueError, SyntaxError):
            arm.program_error(f"{self.name}: bad arguments in {line!r}")
            return False
        if fn == "write_output_integer_register":
            arm.out_int[int(args[0])] = int(args[1])
        elif fn == "write_output_float_register":
            arm.out_double[int(args[0])] = float(args[1])
        elif fn in ("movej", "movel"):
            target = np.array(args[0], dtype=float)
            v = float(kwargs.get("v", 1.05 if fn == "movej" else 0.25))
            a = float(kwargs.get("a", 1.4 if fn == "movej" else 1.2))
            is_pose = bool(kwargs.get("_pose"))
            if fn == "movej":
                q = solve_ik(arm.fk_tcp, pose_to_matrix(target), arm.q) if is_pose else target
                motion = arm.start_movej(q, v, a) if q is not None else None
            else:
                T = pose_to_matrix(target) if is_pose else arm.fk_tcp(target)
                motion = arm.start_movel(T, v, a)
            if motion is None:
                return False
            self.wait = lambda: arm.motion is not motion
        elif fn == "sleep":
            until = now + float(args[0])
            self.wait = lambda: arm.clock.now() >= until
            return True
        elif fn in ("textmsg", "sync"):
            pass
        else:
            arm.program_error(f"{self.name}: unsupported function {fn}()")
            return False
        return True


def _parse_args(src: str) -> tuple[list[Any], dict[str, Any]]:
    """Arguments of a URScript call: numbers, lists and ``p[...]`` poses, positional or keyword."""
    pose = "p[" in src
    src = src.replace("p[", "[")
    call = ast.parse(f"f({src})", mode="eval").body
    assert isinstance(call, ast.Call)
    args = [ast.literal_eval(a) for a in call.args]
    kwargs: dict[str, Any] = {k.arg: ast.literal_eval(k.value) for k in call.keywords if k.arg}
    kwargs["_pose"] = pose
    return args, kwargs


def make_program(parsed: ParsedProgram) -> ControlScript | CustomProgram:
    """The runnable program for a parsed upload."""
    if parsed.name == "rtde_control":
        return ControlScript(parsed)
    return CustomProgram(parsed)
