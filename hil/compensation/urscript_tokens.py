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


@dataclass(frozen=True)
class Token:
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


def tokenize(text: str, name: str) -> Tokens:
    """Tokens of `text`; InputError ``name:line: ...`` for an unterminated string or unbalanced brackets."""
    tokens: list[Token] = []
    line, i, n = 1, 0, len(text)
    while i < n:
        ch = text[i]
        if ch in "\r\n":
            end = i + 2 if text.startswith("\r\n", i) else i + 1
            tokens.append(Token(Kind.NEWLINE, text[i:end], i, end, line))
            line, i = line + 1, end
            continue
        m = _SPACE.match(text, i)
        if m:
            i = m.end()
            continue
        if ch == "#":  # a comment runs to the end of the line
            while i < n and text[i] not in "\r\n":
                i += 1
            continue
        if ch in "\"'":
            j = i + 1
            while j < n and text[j] != ch:
                if text[j] in "\r\n":
                    break
                j += 2 if text[j] == "\\" else 1
            if j >= n or text[j] != ch:
                raise InputError(f"{name}:{line}: a string opened here is not closed on its line")
            tokens.append(Token(Kind.STRING, text[i:j + 1], i, j + 1, line))
            i = j + 1
            continue
        m = _NUMBER.match(text, i)
        if m:
            tokens.append(Token(Kind.NUMBER, m.group(), i, m.end(), line))
            i = m.end()
            continue
        m = _NAME.match(text, i)
        if m:
            tokens.append(Token(Kind.NAME, m.group(), i, m.end(), line))
            i = m.end()
            continue
        if ch in PAIRS:
            kind = Kind.OPEN
        elif ch in PAIRS.values():
            kind = Kind.CLOSE
        elif ch == ",":
            kind = Kind.COMMA
        else:
            kind = Kind.OP
            if text[i:i + 2] in _TWO_CHAR_OPS:
                tokens.append(Token(kind, text[i:i + 2], i, i + 2, line))
                i += 2
                continue
        tokens.append(Token(kind, ch, i, i + 1, line))
        i += 1
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
