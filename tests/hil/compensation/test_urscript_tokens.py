"""The URScript tokenizer: exact spans, numbers in every spelling, strings and comments opaque, brackets
matched, and a malformed program named by its line."""

from __future__ import annotations

import pytest

from hil.compensation.urscript_tokens import Kind, tokenize
from hil.errors import InputError


def _texts(text: str) -> list[tuple[str, str]]:
    return [(t.kind.value, t.text) for t in tokenize(text, "t.script").items]


def test_numbers_in_every_spelling_with_signs_as_operators() -> None:
    toks = _texts("p[-.5, 1e-3, +1, 2., .25E+2, 0.1]")
    numbers = [text for kind, text in toks if kind == "number"]
    assert numbers == [".5", "1e-3", "1", "2.", ".25E+2", "0.1"]
    assert ("op", "-") in toks and ("op", "+") in toks


def test_every_token_knows_its_exact_span_and_line() -> None:
    text = "movel(p[1, 2])\r\n  x = 3 # c\r\ny"
    for tok in tokenize(text, "t.script").items:
        assert text[tok.start:tok.end] == tok.text
    lines = {t.text: t.line for t in tokenize(text, "t.script").items if t.kind is not Kind.NEWLINE}
    assert lines["movel"] == 1 and lines["x"] == 2 and lines["y"] == 3


def test_strings_and_comments_hide_brackets() -> None:
    toks = _texts('popup("p[1,2,3", "x") # movel(p[1,2,3,4,5,6]\nmsg = "say \\"p[\\" ok"  # ) ]')
    assert ("string", '"p[1,2,3"') in toks
    assert ("string", '"say \\"p[\\" ok"') in toks
    assert not any(text == "p" for _, text in toks)  # no pose literal outside the strings


def test_line_ends_inside_brackets_do_not_end_a_statement() -> None:
    toks = tokenize("movel(p[1,\n 2,\r\n 3, 4, 5, 6])\nx = 1\n", "t.script").items
    assert [t.line for t in toks if t.kind is Kind.NEWLINE] == [3, 4]


@pytest.mark.parametrize(("text", "says"), [
    ("movel(p[1, 2, 3, 4, 5, 6)\n", "t.script:1: ')' closes the '[' opened on line 1"),
    ("x = 1\ny = 2)\n", "t.script:2: ')' closes no bracket"),
    ("x = 1\nmovel(p[1, 2, 3, 4, 5, 6]\nend\n", "t.script:2: '(' is never closed"),
    ("x = 1\r\n\r\npopup(\"open\n", "t.script:3: a string opened here is not closed"),
])
def test_malformed_programs_are_named_by_line(text: str, says: str) -> None:
    with pytest.raises(InputError) as err:
        tokenize(text, "t.script")
    assert str(err.value).startswith(says)
