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


def test_operators_lone_marks_and_odd_characters_are_single_tokens() -> None:
    toks = _texts("a<=b != c == d >= e < f . g $ h é\x85i\r'\\'' + \"\\\\\"")
    assert toks == [("name", "a"), ("op", "<="), ("name", "b"), ("op", "!="), ("name", "c"), ("op", "=="),
                    ("name", "d"), ("op", ">="), ("name", "e"), ("op", "<"), ("name", "f"), ("op", "."),
                    ("name", "g"), ("op", "$"), ("name", "h"), ("op", "é"), ("op", "\x85"), ("name", "i"),
                    ("newline", "\r"), ("string", "'\\''"), ("op", "+"), ("string", '"\\\\"')]


def test_a_long_program_reads_in_linear_time() -> None:
    """Guards the scan's cost against a quadratic regression: 16 times the program is not more than
    about 16 times the time (a quadratic scan would be 256 times). Ratios, so the host's speed cancels."""
    import time

    line = "  movel(p[0.1, -0.4, 0.2, 0, 3.14, 0], a=1.2, v=0.25)  # go\n  x = p[1, 2, 3, 4, 5, 6]\n"

    def seconds(n: int) -> float:
        text = line * n
        best = float("inf")
        for _ in range(3):
            t0 = time.perf_counter()
            tokenize(text, "t.script")
            best = min(best, time.perf_counter() - t0)
        return best

    assert seconds(16_000) < 60 * seconds(1_000)
