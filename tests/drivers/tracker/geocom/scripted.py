"""A scripted line transport for exact request/reply exchange tests (pymeasure style)."""

from __future__ import annotations

from drivers.tracker.errors import TrackerTimeout


class ScriptedTransport:
    """Asserts each written request byte-for-byte and then makes the scripted lines readable."""

    terminator = b"\r\n"

    def __init__(self, script: list[tuple[bytes, list[bytes]]]) -> None:
        self.script = list(script)
        self.lines: list[bytes] = []
        self.written: list[bytes] = []
        self.discards = 0

    def write(self, data: bytes) -> None:
        assert self.script, f"unexpected write {data!r}"
        expected, replies = self.script.pop(0)
        self.written.append(data)
        assert data == expected, f"wrote {data!r}, expected {expected!r}"
        self.lines.extend(replies)

    def read_line(self, deadline: float) -> bytes:
        if self.lines:
            return self.lines.pop(0)
        raise TrackerTimeout("scripted transport has no more lines")

    def discard_input(self) -> None:
        self.discards += 1
        self.lines.clear()

    def done(self) -> bool:
        return not self.script and not self.lines
