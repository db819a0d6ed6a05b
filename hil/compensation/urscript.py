"""Compensating a URScript program: every pose literal that is a move target, rewritten in place.

What is a target (URScript manual, module motion):

* a ``p[...]`` literal given as the target of ``movel``, ``movej``, ``movep`` (first argument) or
  ``movec`` (via and to point), or as the pose ``x`` of ``get_inverse_kin`` (``movej(get_inverse_kin(
  p[...], qnear=[...]))``), by position or by keyword (``pose=``, ``q=``, ``pose_via=``, ``pose_to=``,
  ``x=``);
* the literal assigned to a variable that such a move goes to (``global Waypoint_1_p=p[...]`` then
  ``movel(Waypoint_1_p)``, as Polyscope writes programs). A pose variable no move goes to (a feature,
  a plane, an offset) is left as it is and listed: compensating a frame would move what is built on it.

Left alone, byte for byte: ``set_tcp(p[...])`` (it sets the TCP the following targets are compensated
for: the program's current one, else the TCP the caller gives, else the flange), offsets and frames
inside ``pose_trans``, ``pose_add``, ``pose_inv`` or any other expression, literals holding variables,
and every comment, string (``"p["`` in a popup stays text), space and line ending (CRLF stays CRLF):
only the characters of a rewritten literal change.

A move whose target is computed at run time (an expression, a literal holding variables, a variable
assigned from one, a parameter) cannot be compensated statically: it is listed in the summary with its
line and the reason, never dropped silently.

The branch of each target is chosen near, first, its Polyscope joint twin (``Waypoint_1_q`` beside
``Waypoint_1_p``) or the ``qnear`` its ``get_inverse_kin`` names; else the program's preceding joint
target in text order (a ``movej([...])`` literal, or the previous compensated target); else `near`.
The program is read in text order, not executed: a TCP set inside a branch counts from its line on.

With ``joints``, a pose literal that is a move's argument is written as the joint list the accurate
model solves it to (``movel``, ``movep`` and ``movec`` take joint positions and run the controller's
forward kinematics on them, which is exactly the compensated pose; ``movej`` moves to them). Pose
variables stay poses (compensated): they may be used where joints are not accepted. Between targets the
controller interpolates in its own model; a ``movec`` via point uses only its position, so the via is
compensated for the orientation written there.

URScript has no maintained Python parser (see `hil.compensation.urscript_tokens`); this reads only the
structure above.
"""

from __future__ import annotations

import bisect
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from hil.arm.ik import UnreachableError
from hil.compensation.poses import check_pose, format_number, to_se3
from hil.compensation.solve import Compensator
from hil.compensation.summary import Skipped, Summary
from hil.compensation.urscript_tokens import Kind, Tokens, tokenize
from hil.errors import InputError
from hil.files.quantities import real

#: Moves and the (position, keyword) of each argument that is an absolute target.
MOVES: dict[str, tuple[tuple[int, str], ...]] = {
    "movel": ((0, "pose"),),
    "movej": ((0, "q"),),
    "movep": ((0, "pose"),),
    "movec": ((0, "pose_via"), (1, "pose_to")),
}
INVERSE_KIN = "get_inverse_kin"  # get_inverse_kin(x, qnear, maxPositionError, maxOrientationError, tcp)
SET_TCP = "set_tcp"
#: Names that read as numbers but are not URScript (nan and inf written by a tool that printed floats):
#: refused inside a literal rather than taken for a variable the program computes at run time.
NOT_A_NUMBER = frozenset({"nan", "inf", "infinity"})
#: Built-ins that return joint positions: a move to their result needs no compensation.
JOINT_FUNCTIONS = frozenset({"get_actual_joint_positions", "get_target_joint_positions", INVERSE_KIN,
                             "get_actual_joint_positions_history"})
_DEFINITIONS = frozenset({"def", "thread"})


@dataclass(frozen=True)
class Arg:
    keyword: str | None
    start: int  # token range of the value: [start, end)
    end: int


@dataclass(frozen=True)
class Call:
    name: str
    index: int  # token index of the name
    line: int
    args: tuple[Arg, ...]

    def arg(self, position: int, keyword: str) -> Arg | None:
        """The argument given at `position` (counting positional ones) or by `keyword`."""
        named = [a for a in self.args if a.keyword == keyword]
        if named:
            return named[0]
        positional = [a for a in self.args if a.keyword is None]
        return positional[position] if position < len(positional) else None


@dataclass(frozen=True)
class Literal:
    """A ``p[...]`` or ``[...]`` literal: its numbers (None when an element is not a number)."""

    values: tuple[float, ...] | None
    count: int
    start: int  # character span of the whole literal
    end: int
    comma: str  # the separator the program writes (", " or ",")


@dataclass
class Assign:
    """``[global|local] name = value`` at the start of a statement."""

    var: str
    index: int
    line: int
    pose: Literal | None = None  # a p[...] literal
    joints: Literal | None = None  # a [...] literal
    call: str | None = None  # the function the value is a call of
    uses: list[Site] = field(default_factory=list)  # moves that go to this variable


@dataclass
class Site:
    """One place a move names a target."""

    line: int
    what: str  # the function: movel, get_inverse_kin, ...
    index: int  # token index of the target
    tcp: pin.SE3 | None  # the TCP in effect (None: set at run time, see `tcp_line`)
    tcp_line: int
    qnear: np.ndarray | None = None
    literal: Literal | None = None
    as_joints: bool = False  # a move's argument: may be written as joints


class _Program:
    """The structure of one program (calls, assignments) over its tokens."""

    def __init__(self, text: str, name: str) -> None:
        self.text, self.name = text, name
        toks: Tokens = tokenize(text, name)
        self.items, self.match = toks.items, toks.match
        self.calls: list[Call] = []
        self.assigns: dict[str, list[Assign]] = {}
        self._scan()

    # --- pieces of the token list -------------------------------------------------------------
    def _split(self, open_index: int) -> list[tuple[int, int]]:
        """Token ranges of the comma-separated parts inside the bracket opened at `open_index`."""
        close = self.match[open_index]
        parts, start, k = [], open_index + 1, open_index + 1
        while k < close:
            tok = self.items[k]
            if tok.kind is Kind.OPEN:
                k = self.match[k] + 1
                continue
            if tok.kind is Kind.COMMA:
                parts.append((start, k))
                start = k + 1
            k += 1
        if start < close or parts:
            parts.append((start, close))
        return parts

    def literal(self, a: int, b: int) -> Literal | None:
        """The ``p[...]`` (pose) or ``[...]`` literal that is exactly tokens [a, b), else None."""
        items = self.items
        is_pose = (b - a >= 3 and items[a].kind is Kind.NAME and items[a].text == "p"
                   and items[a + 1].text == "[" and self.match.get(a + 1) == b - 1)
        is_list = not is_pose and items[a].text == "[" and self.match.get(a) == b - 1
        if not (is_pose or is_list):
            return None
        open_index = a + 1 if is_pose else a
        values: list[float] | None = []
        parts = self._split(open_index)
        for s, e in parts:
            toks = items[s:e]
            sign = 1.0
            if len(toks) == 2 and toks[0].text in "+-" and toks[0].kind is Kind.OP:
                sign, toks = (-1.0 if toks[0].text == "-" else 1.0), toks[1:]
            if len(toks) == 1 and toks[0].kind is Kind.NAME and toks[0].text.lower() in NOT_A_NUMBER:
                raise InputError(f"{self.name}:{toks[0].line}: {toks[0].text} in a literal is not a finite "
                                 "number (URScript has no such constant)")
            if values is not None and len(toks) == 1 and toks[0].kind is Kind.NUMBER:
                values.append(real(sign * float(toks[0].text), f"{self.name}:{toks[0].line}", toks[0].text))
            else:
                values = None
        inside = self.text[items[open_index].end:items[b - 1].start]
        numbers = None if values is None else tuple(values)
        return Literal(numbers, len(parts), items[a].start, items[b - 1].end, ", " if ", " in inside else ",")

    def call_name(self, a: int, b: int) -> str | None:
        """The function name when tokens [a, b) are exactly one call."""
        items = self.items
        if (b - a >= 3 and items[a].kind is Kind.NAME and items[a + 1].text == "("
                and self.match.get(a + 1) == b - 1):
            return items[a].text
        return None

    def name_of(self, a: int, b: int) -> str | None:
        return self.items[a].text if b == a + 1 and self.items[a].kind is Kind.NAME else None

    def source(self, a: int, b: int, limit: int = 48) -> str:
        """The program text of tokens [a, b) (shortened), to name an expression in the summary."""
        text = " ".join(self.text[self.items[a].start:self.items[b - 1].end].split())
        return text if len(text) <= limit else text[:limit - 3] + "..."

    # --- structure ----------------------------------------------------------------------------
    def _scan(self) -> None:
        items = self.items
        n = len(items)
        statement = True
        for k, tok in enumerate(items):
            if tok.kind is Kind.NEWLINE:
                statement = True
                continue
            if statement:
                self._assignment(k)
            statement = False
            if (tok.kind is Kind.NAME and k + 1 < n and items[k + 1].text == "("
                    and not (k and items[k - 1].text in _DEFINITIONS)):
                args = []
                for s, e in self._split(k + 1):
                    if e - s >= 2 and items[s].kind is Kind.NAME and items[s + 1].text == "=":
                        args.append(Arg(items[s].text, s + 2, e))
                    else:
                        args.append(Arg(None, s, e))
                self.calls.append(Call(tok.text, k, tok.line, tuple(args)))

    def _assignment(self, k: int) -> None:
        items = self.items
        if items[k].kind is Kind.NAME and items[k].text in ("global", "local"):
            k += 1
        if not (k + 2 < len(items) and items[k].kind is Kind.NAME and items[k + 1].text == "="):
            return
        end = k + 2
        while end < len(items) and items[end].kind is not Kind.NEWLINE:
            end += 1
        a = Assign(items[k].text, k, items[k].line)
        value = self.literal(k + 2, end)
        if value is not None and items[k + 2].text == "p":
            a.pose = value
        elif value is not None:
            a.joints = value
        else:
            a.call = self.call_name(k + 2, end)
        self.assigns.setdefault(a.var, []).append(a)

    def reaching(self, var: str, index: int) -> Assign | None:
        """The assignment of `var` a use at token `index` sees, in text order: the last one before it,
        else the first after it (a function defined above the globals it uses)."""
        found = self.assigns.get(var)
        if not found:
            return None
        k = bisect.bisect_left(found, index, key=lambda a: a.index)  # `found` is in text order
        return found[k - 1] if k else found[0]


def _numbers(lit: Literal | None) -> np.ndarray | None:
    return None if lit is None or lit.values is None else np.array(lit.values)


def _joint_value(prog: _Program, arg: Arg | None) -> np.ndarray | None:
    """Joint positions an argument holds, when known statically (a literal, or a variable set to one)."""
    if arg is None:
        return None
    lit = prog.literal(arg.start, arg.end)
    if lit is not None and prog.items[arg.start].text == "[":
        q = _numbers(lit)
        return q if q is not None and q.size == 6 else None
    var = prog.name_of(arg.start, arg.end)
    if var is not None:
        a = prog.reaching(var, arg.start)
        q = None if a is None else _numbers(a.joints)
        return q if q is not None and q.size == 6 else None
    return None


def _pose_values(prog: _Program, lit: Literal, line: int, what: str) -> np.ndarray:
    """The six numbers of a pose literal used as a pose (InputError naming the line otherwise)."""
    values = _numbers(lit)
    assert values is not None
    if values.size != 6:
        raise InputError(f"{prog.name}:{line}: {what}: p[...] has {values.size} element"
                         f"{'s' if values.size != 1 else ''}, a pose has 6")
    return check_pose(values, f"{prog.name}:{line}: {what}")


@dataclass
class _Analysis:
    sites: list[Site] = field(default_factory=list)  # targets that are literals
    joint_targets: list[tuple[int, np.ndarray]] = field(default_factory=list)  # (token index, q)
    skipped: list[Skipped] = field(default_factory=list)  # (not compensated)


def _analyse(prog: _Program, default_tcp: pin.SE3) -> _Analysis:
    """Walk the calls in text order: the TCP in effect, the target of every move, and why not."""
    out = _Analysis()
    tcp: pin.SE3 | None = default_tcp
    tcp_line = 0
    for call in prog.calls:
        if call.name == SET_TCP:
            arg = call.arg(0, "pose")
            tcp, tcp_line = _set_tcp(prog, call, arg), call.line
            continue
        if call.name in MOVES:
            targets = [(call.arg(pos, kw), True) for pos, kw in MOVES[call.name]]
            qnear, site_tcp = None, tcp
        elif call.name == INVERSE_KIN:
            targets = [(call.arg(0, "x"), False)]
            qnear = _joint_value(prog, call.arg(1, "qnear"))
            given = call.arg(4, "tcp")
            site_tcp = tcp
            if given is not None:
                lit = prog.literal(given.start, given.end)
                if lit is None or lit.values is None or prog.items[given.start].text != "p":
                    out.skipped.append(Skipped(call.line, call.name,
                                               "its tcp argument is computed at run time"))
                    continue
                site_tcp = to_se3(_pose_values(prog, lit, call.line, "tcp"))
        else:
            continue
        for arg, as_joints in targets:
            if arg is None:
                continue
            _target(prog, out, call, arg, Site(call.line, call.name, arg.start, site_tcp, tcp_line, qnear,
                                                 as_joints=as_joints))
    return out


def _set_tcp(prog: _Program, call: Call, arg: Arg | None) -> pin.SE3 | None:
    """The TCP a ``set_tcp`` sets, or None when it is known only at run time."""
    if arg is None:
        return None
    lit = prog.literal(arg.start, arg.end)
    if lit is not None and prog.items[arg.start].text != "p":
        lit = None  # a joint list is no TCP
    var = prog.name_of(arg.start, arg.end)
    if var is not None:  # set_tcp(Tool_1), the variable set to a literal
        a = prog.reaching(var, arg.start)
        lit = a.pose if a is not None else None
    if lit is None or lit.values is None:
        return None
    return to_se3(_pose_values(prog, lit, call.line, SET_TCP))


def _target(prog: _Program, out: _Analysis, call: Call, arg: Arg, site: Site) -> None:
    """Classify one target argument: a literal site, a variable's use, a joint target, or skipped."""
    a, b = arg.start, arg.end
    lit = prog.literal(a, b)
    if lit is not None and prog.items[a].text == "p":
        if lit.values is None:
            out.skipped.append(Skipped(call.line, call.name,
                                       "the pose holds expressions (computed at run time)"))
            return
        _pose_values(prog, lit, call.line, call.name)
        site.literal = lit
        out.sites.append(site)
        return
    if lit is not None:  # [...]: joint positions
        q = _numbers(lit)
        if q is not None and q.size == 6:
            out.joint_targets.append((a, q))
        return
    var = prog.name_of(a, b)
    if var is not None:
        assign = prog.reaching(var, a)
        if assign is None:
            reason = f"{var} is not assigned in this program (a parameter, or set by the installation)"
        elif assign.pose is not None and assign.pose.values is not None:
            _pose_values(prog, assign.pose, assign.line, var)
            assign.uses.append(site)
            return
        elif assign.joints is not None:
            q = _numbers(assign.joints)
            if q is not None and q.size == 6:
                out.joint_targets.append((a, q))
            return
        elif assign.call in JOINT_FUNCTIONS:
            return
        elif assign.pose is not None:
            reason = f"{var} (line {assign.line}) holds expressions (computed at run time)"
        else:
            reason = f"{var} is computed at run time (line {assign.line})"
        out.skipped.append(Skipped(call.line, call.name, reason))
        return
    name = prog.call_name(a, b)
    if name in JOINT_FUNCTIONS:  # joints (get_inverse_kin's own target is a site of its own)
        return
    out.skipped.append(Skipped(call.line, call.name, f"{prog.source(a, b)} is computed at run time"))


def _format(values: np.ndarray, pose: bool, comma: str) -> str:
    return ("p[" if pose else "[") + comma.join(format_number(v) for v in values) + "]"


def scan_program(text: str, name: str, tcp: pin.SE3) -> int:
    """Read `text` as `compensate_program` does before it solves anything (tokens, calls, assignments,
    targets); the number of targets found. InputError for a malformed program, as there."""
    found = _analyse(_Program(text, name), tcp)
    return len(found.sites) + len(found.joint_targets)


def compensate_program(text: str, name: str, compensator: Compensator, near: Sequence[float],
                       *, joints: bool = False) -> tuple[str, Summary]:
    """The compensated program text and its summary (see the module docstring).

    `compensator.tcp` is the TCP before the program's first ``set_tcp``. InputError ``name:line: ...``
    for a malformed program or a target the arm cannot reach (then nothing is returned, so nothing is
    written).
    """
    prog = _Program(text, name)
    found = _analyse(prog, compensator.tcp)
    summary = Summary(name, "urscript", joints=joints)
    by_tcp: dict[tuple[float, ...], Compensator] = {}

    def solver(tcp: pin.SE3) -> Compensator:
        key = tuple(np.round(np.r_[tcp.translation, tcp.rotation.ravel()], 15))
        if key not in by_tcp:
            by_tcp[key] = Compensator(compensator.accurate, compensator.controller, tcp)
        return by_tcp[key]

    # the jobs in text order: joint targets (seeds), literal sites, and the assignments moves go to
    jobs: list[tuple[int, object]] = [(i, q) for i, q in found.joint_targets]
    jobs += [(s.index, s) for s in found.sites]
    for assigns in prog.assigns.values():
        for a in assigns:
            if a.pose is None or a.pose.values is None:
                continue
            if not a.uses:
                summary.left_alone.append(Skipped(a.line, a.var,
                                                  "no move goes to it (a frame or an offset?)"))
                continue
            jobs.append((a.index, a))
    jobs.sort(key=lambda job: job[0])
    skipped = list(found.skipped)
    replacements: list[tuple[int, int, str]] = []
    q = np.asarray(near, dtype=float)
    for _, job in jobs:
        if isinstance(job, np.ndarray):
            q = job
            continue
        if isinstance(job, Site):
            lit, line, what = job.literal, job.line, job.what
            if job.tcp is None:
                skipped.append(Skipped(line, what, f"the TCP is set at run time (line {job.tcp_line})"))
                continue
            tcp, seed = job.tcp, job.qnear
            write_joints = joints and job.as_joints
        else:
            assert isinstance(job, Assign)
            lit, line, what = job.pose, job.line, job.var
            tcp_of = _common_tcp(job)
            if isinstance(tcp_of, str):
                skipped += [Skipped(u.line, u.what, f"{job.var}: {tcp_of}") for u in job.uses]
                continue
            tcp, seed, write_joints = tcp_of, _paired_joints(prog, job), False
        assert lit is not None
        target = to_se3(_numbers(lit))  # type: ignore[arg-type]
        try:
            c = solver(tcp).solve(target, q if seed is None else seed)
        except UnreachableError as exc:
            raise UnreachableError(f"{name}:{line}: {what}: {exc}") from None
        summary.add(line, what, c)
        if write_joints:
            replacements.append((lit.start, lit.end, _format(c.q, False, lit.comma)))
            summary.as_joints += 1
        else:
            replacements.append((lit.start, lit.end, _format(_pose_vector(c.command), True, lit.comma)))
        q = c.q
    summary.not_compensated = sorted(skipped, key=lambda s: s.line)
    summary.left_alone.sort(key=lambda s: s.line)
    return splice(text, replacements), summary


def _pose_vector(M: pin.SE3) -> np.ndarray:
    return np.r_[M.translation, pin.log3(M.rotation)]


def _common_tcp(assign: Assign) -> pin.SE3 | str:
    """The one TCP every move to `assign`'s variable uses, or why there is none."""
    unknown = [u for u in assign.uses if u.tcp is None]
    if unknown:
        return f"the TCP is set at run time (line {unknown[0].tcp_line})"
    first = assign.uses[0].tcp
    assert first is not None
    for u in assign.uses[1:]:
        assert u.tcp is not None
        if not first.isApprox(u.tcp, 1e-12):
            return (f"moves go to it under different TCPs (lines {assign.uses[0].line} and {u.line}): "
                    "one literal cannot serve both")
    return first


def _paired_joints(prog: _Program, assign: Assign) -> np.ndarray | None:
    """The joints a pose variable's branch is chosen near: Polyscope's ``Name_q`` twin of ``Name_p``,
    else the ``qnear`` of a ``get_inverse_kin`` that names it."""
    if assign.var.endswith("_p"):
        twin = prog.assigns.get(assign.var[:-2] + "_q")
        if twin:
            q = _numbers(twin[0].joints)
            if q is not None and q.size == 6:
                return q
    return next((u.qnear for u in assign.uses if u.qnear is not None), None)


def splice(text: str, replacements: Sequence[tuple[int, int, str]]) -> str:
    """`text` with each [start, end) span replaced; everything between the spans copied as it is."""
    out, at = [], 0
    for start, end, new in sorted(replacements):
        out += [text[at:start], new]
        at = end
    out.append(text[at:])
    return "".join(out)
