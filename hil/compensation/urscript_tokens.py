"""A small tokenizer for URScript: enough structure to find pose literals and the calls they sit in.

URScript has no maintained Python parser (UR publishes the language only as its script manual; the
controller's own parser is closed), and a compensation must not reformat a program anyway: it replaces
the text of a few literals and leaves every other byte alone. So this reads only what that needs —
strings (``"..."``, where ``p[`` is just text), ``#`` comments, brackets (matched, with the line each
opened on), names, numbers (``1``, ``.5``, ``1.``, ``1e-3``; a sign is a separate operator token, so
``-.5`` is ``-`` then ``.5``), commas, operators and line ends — each token with its exact character
span, so the text around a replaced span is copied, never re-created. Line ends inside brackets do not
end a statement and are dropped from the tokens a parser sees.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from enum import Enum
from typing import NamedTuple

from hil.errors import InputError


class Kind(Enum):
    NAME = "name"
    NUMBER = "number"
    STRING = "string"
    OPEN = "open"
    CLOSE = "close"
    COMMA = "comma"
    OP = "op"
    NEWLINE = "newline"


class Token(NamedTuple):
    """One token (a named tuple: a program has hundreds of thousands, and tuples are made fast)."""

    kind: Kind
    text: str
    start: int  # character offsets into the program text: [start, end)
    end: int
    line: int  # 1-based


PAIRS = {"(": ")", "[": "]", "{": "}"}
_NUMBER = re.compile(r"(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_SPACE = re.compile(r"[ \t\f\v\ufeff]+")
_TWO_CHAR_OPS = ("==", "!=", "<=", ">=")


@dataclass(frozen=True)
class Tokens:
    """The significant tokens of a program (no spaces, comments or line ends inside brackets) and,
    for every opening bracket, the index of its closing one."""

    items: list[Token]
    match: dict[int, int]  # index of an OPEN token -> index of its CLOSE token


_MASTER = re.compile("|".join((
    r"(?P<newline>\r\n|\r|\n)",
    r"(?P<space>[ \t\f\v\ufeff]+)",
    r"(?P<comment>#[^\r\n]*)",  # a comment runs to the end of the line
    r"(?P<string>\"(?:[^\"\\\r\n]|\\[\s\S])*\"|'(?:[^'\\\r\n]|\\[\s\S])*')",
    r"(?P<unclosed>[\"'])",
    r"(?P<number>" + _NUMBER.pattern + ")",
    r"(?P<name>" + _NAME.pattern + ")",
    r"(?P<open>[([{])",
    r"(?P<close>[)\]}])",
    r"(?P<comma>,)",
    r"(?P<op>" + "|".join(map(re.escape, _TWO_CHAR_OPS)) + r"|[\s\S])",
)))
_KINDS = {"string": Kind.STRING, "number": Kind.NUMBER, "name": Kind.NAME, "open": Kind.OPEN,
          "close": Kind.CLOSE, "comma": Kind.COMMA, "op": Kind.OP}


def tokenize(text: str, name: str) -> Tokens:
    """Tokens of `text`; InputError ``name:line: ...`` for an unterminated string or unbalanced brackets.

    One master expression scans the text (the `re` module's loop in C), which reads about ten times
    faster than stepping through it character by character in Python."""
    tokens: list[Token] = []
    line = 1
    kinds = _KINDS
    for m in _MASTER.finditer(text):
        group = m.lastgroup
        if group == "space" or group == "comment":
            continue
        if group == "newline":
            tokens.append(Token(Kind.NEWLINE, m.group(), m.start(), m.end(), line))
            line += 1
            continue
        if group == "unclosed":
            raise InputError(f"{name}:{line}: a string opened here is not closed on its line")
        assert group is not None
        tokens.append(Token(kinds[group], m.group(), m.start(), m.end(), line))
    return _match(tokens, name)


def _match(tokens: list[Token], name: str) -> Tokens:
    """Pair the brackets and drop the line ends inside them."""
    items: list[Token] = []
    match: dict[int, int] = {}
    stack: list[int] = []  # indices into `items` of the open brackets
    for tok in tokens:
        if tok.kind is Kind.NEWLINE and stack:
            continue
        if tok.kind is Kind.OPEN:
            stack.append(len(items))
        elif tok.kind is Kind.CLOSE:
            if not stack:
                raise InputError(f"{name}:{tok.line}: '{tok.text}' closes no bracket")
            opened = items[stack[-1]]
            if PAIRS[opened.text] != tok.text:
                raise InputError(f"{name}:{tok.line}: '{tok.text}' closes the '{opened.text}' opened on line "
                                 f"{opened.line}")
            match[stack.pop()] = len(items)
        items.append(tok)
    if stack:
        opened = items[stack[-1]]
        raise InputError(f"{name}:{opened.line}: '{opened.text}' is never closed")
    return Tokens(items, match)
