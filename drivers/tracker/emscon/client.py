"""emScon's command/answer pairing over one connection, and the asynchronous packets around it.

TPI has no transaction ids: a command is answered by a packet of the same ``ES_Command``, and results
(measurements), errors and status events arrive asynchronously in between. The client keeps one command
in flight; while it waits it routes every other packet to a queue (`singles`, `multis`, `errors`) or to
the beam state (``MeasStatus_NotReady`` / ``_Ready`` events), so nothing that arrives early is lost and
nothing stale is taken for an answer. A wait that ends at its deadline raises `TrackerTimeout` and marks
the connection `dirty`: a late answer could otherwise be paired with the next command, so the owner
reconnects before the next one.
"""

from __future__ import annotations

import logging
import time
from collections import deque
from collections.abc import Callable

from drivers.tracker.emscon.packets import (
    Answer,
    Command,
    ErrorResponse,
    MultiMeasResult,
    PacketError,
    ReflectorPosResult,
    ResultStatus,
    SingleMeasResult,
    StatusChange,
    SystemStatusChange,
    decode_reply,
    encode_command,
    status_name,
)
from drivers.tracker.emscon.transport import TcpTransport
from drivers.tracker.errors import ConnectionLost, GarbledReply, LinkError, TrackerTimeout

log = logging.getLogger(__name__)


class EmsconClient:
    """Send a command, get its answer; everything else that arrives is kept for whoever waits on it."""

    def __init__(self, transport: TcpTransport, timeout: float = 3.0) -> None:
        self.transport = transport
        self.timeout = timeout
        self.singles: deque[SingleMeasResult] = deque()
        self.multis: deque[MultiMeasResult] = deque()
        self.errors: deque[ErrorResponse] = deque()
        self.beam_locked: bool | None = None  # from the server's MeasStatus events (None: no event yet)
        self.beam_changes = 0  # NotReady events seen (a stream reports each loss once)
        self.dirty = False
        self.server_closing = False

    def reset(self) -> None:
        """Forget everything of a previous connection."""
        self.singles.clear()
        self.multis.clear()
        self.errors.clear()
        self.beam_locked = None
        self.dirty = False
        self.server_closing = False

    # --- one command -----------------------------------------------------------------------------
    def request(self, command: Command, *params: object, timeout: float | None = None) -> Answer:
        """Send `command` and return its answer (any status: the caller judges it)."""
        return self.request_many(command, *params, timeout=timeout)[0]

    def request_many(self, command: Command, *params: object, timeout: float | None = None) -> list[Answer]:
        """Commands answered by several packets (GetReflectors: one per reflector; the first says how
        many)."""
        if self.dirty:
            raise LinkError("the emScon connection is out of step; reconnect first")
        packet = encode_command(command, *params)
        self.transport.send(packet)
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        answers: list[Answer] = []
        expected = 1
        while len(answers) < expected:
            reply = self._next(deadline, f"ES_C_{command.name}")
            if isinstance(reply, Answer):
                if reply.command != command:
                    log.warning("emScon: dropped an answer to ES_C_%s while waiting for ES_C_%s",
                                reply.command, command.name)
                    continue
                answers.append(reply)
                if command == Command.GET_REFLECTORS and reply.ok and reply.values:
                    expected = max(1, int(reply.values[0]))
            else:
                refused = ResultStatus.MultiConnectionsNotAllowed
                if isinstance(reply, ErrorResponse) and reply.status == refused:
                    self.dirty = True
                    self.transport.close()
                    raise ConnectionLost("another client is connected to the emScon server "
                                         "(ES_RS_MultiConnectionsNotAllowed): close it first")
                self._route(reply)
        return answers

    # --- asynchronous packets --------------------------------------------------------------------
    def wait(self, ready: Callable[[], bool], deadline: float, what: str) -> None:
        """Read and route packets until `ready()` holds (TrackerTimeout at `deadline`)."""
        while not ready():
            self._route(self._next(deadline, what))

    def pump(self, deadline: float) -> bool:
        """Route the next packet if one arrives by `deadline`; False (and nothing marked) if none did."""
        reply = self._next_or_none(deadline)
        if reply is None:
            return False
        self._route(reply)
        return True

    def poll(self) -> None:
        """Route whatever has already arrived, without waiting."""
        while True:
            reply = self._next_or_none(time.monotonic())
            if reply is None:
                return
            self._route(reply)

    def _route(self, reply: object) -> None:
        if isinstance(reply, SingleMeasResult):
            self.singles.append(reply)
        elif isinstance(reply, MultiMeasResult):
            self.multis.append(reply)
        elif isinstance(reply, ErrorResponse):
            log.info("emScon error packet: ES_C_%s %s", reply.command, status_name(reply.status))
            self.errors.append(reply)
        elif isinstance(reply, StatusChange):
            if reply.change == SystemStatusChange.MEAS_STATUS_NOT_READY:
                self.beam_locked = False
                self.beam_changes += 1
            elif reply.change == SystemStatusChange.MEAS_STATUS_READY:
                self.beam_locked = True
            elif reply.change == SystemStatusChange.SERVER_CLOSING:
                self.server_closing = True
        elif isinstance(reply, ReflectorPosResult):
            pass  # position updates while locked: not used
        elif isinstance(reply, Answer):
            log.warning("emScon: unsolicited answer to ES_C_%s dropped", reply.command)

    def _next(self, deadline: float, what: str) -> object:
        reply = self._next_or_none(deadline)
        if reply is None:
            self.dirty = True
            raise TrackerTimeout(f"emScon: no answer to {what} within the timeout")
        return reply

    def _next_or_none(self, deadline: float) -> object | None:
        try:
            packet = self.transport.receive(deadline)
        except (ConnectionLost, GarbledReply):
            self.dirty = True
            raise
        if packet is None:
            return None
        try:
            return decode_reply(packet)
        except PacketError as exc:
            self.dirty = True
            self.transport.close()
            raise GarbledReply(f"emScon: undecodable packet ({exc}); reconnecting") from None
