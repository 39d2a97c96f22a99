"""Typed numbers (issue 29): read as a person means them, or refused with a message that
names the field and what it takes; the field and its slider keep the value in force.

Truth: what the text means to a person (``1e5`` is 100,000, ``5,5`` is 5.5 with a decimal
comma) and the parameters' own bounds (param).
"""

from __future__ import annotations

import pytest

from app.state import DashboardState
from app.state.analysis import AnalysisState
from app.views.controls import Controls
from app.views.typed import NumberField, TypedInputError, parse_number


@pytest.mark.parametrize(
    "text, integer, value",
    [
        ("1e5", True, 100_000),
        ("1E5", False, 100_000.0),
        ("2.5e-1", False, 0.25),
        ("1.5", False, 1.5),
        ("5,5", False, 5.5),
        ("2,5", False, 2.5),
        (" 12 ", True, 12),
        ("10 000", True, 10_000),
        ("10,000", True, 10_000),
        ("1,000,000", True, 1_000_000),
        ("1,234.5", False, 1234.5),
        ("-3", True, -3),
        (".5", False, 0.5),
        ("150.", False, 150.0),
        ("2.0", True, 2),
    ],
)
def test_a_number_is_read_as_a_person_means_it(text, integer, value):
    got = parse_number(text, integer)
    assert got == value and type(got) is (int if integer else float)


@pytest.mark.parametrize(
    "text, integer, words",
    [
        ("abc", False, "'abc' is not a number"),
        ("abc", True, "'abc' is not a number"),
        ("", False, "nothing typed"),
        ("1.5", True, "'1.5' is not a whole number"),
        ("5,5", True, "'5,5' is not a whole number"),
        ("1,000", False, "ambiguous"),
        ("1,2,3", False, "one decimal mark"),
        ("1.2,3", False, "one decimal mark"),
        ("inf", False, "not a number"),
        ("nan", False, "not a number"),
        ("0x10", True, "not a number"),
        ("1_000", True, "not a number"),
        ("1e400", False, "too large"),
        ("12abc", False, "not a number"),
    ],
)
def test_a_text_that_is_not_a_number_of_the_field_is_refused(text, integer, words):
    with pytest.raises(TypedInputError, match=words):
        parse_number(text, integer)
    assert issubclass(TypedInputError, ValueError)


#: Every typed field of the page: (object, parameter, what 1e5 / 1.5 / 5,5 / abc give:
#: the value read, or None for a refusal).
TYPED = {
    "noise.rounds": (100_000, None, None, None),
    "noise.seed": (100_000, None, None, None),
    "noise.single_round": (None, None, None, None),  # 0 .. R - 1 with R = 10,000
    "noise.noise": (None, 1.5, 5.5, None),  # 0 .. 99.99 %
    "truncation.threshold": (None, 1.5, 5.5, None),  # 0.1 .. 1000 %
    "truncation.f_max": (None, 1.5, 5.5, None),  # 1 .. 1000 Hz
}


@pytest.mark.parametrize("key", list(TYPED))
def test_every_typed_field_reads_or_refuses_with_a_message(key):
    state = DashboardState()
    controls = Controls(state=state)
    field = controls.fields[key]
    group, name = key.split(".")
    obj = getattr(state, group)
    for text, want in zip(("1e5", "1.5", "5,5", "abc"), TYPED[key], strict=True):
        before = getattr(obj, name)
        field.text.value = text
        if want is None:  # refused: a message naming the field; nothing changed
            assert field.message.visible, (key, text)
            assert field.label in field.message.object and "still" in field.message.object
            assert getattr(obj, name) == before
            assert field.text.value == f"{before:g}"
            if field.bar is not None:  # the slider keeps the value in force too
                assert field.bar.value == before
        else:
            assert getattr(obj, name) == want and not field.message.visible, (key, text)
            if field.bar is not None:
                assert field.bar.value == want


def test_the_slider_and_the_field_stay_together():
    state = DashboardState()
    field = Controls(state=state).fields["truncation.threshold"]
    field.bar.value = 12.0  # a drag
    assert state.truncation.threshold == 12.0 and field.text.value == "12"
    field.text.value = "0"  # refused (below 0.1): both still show 12
    assert field.message.visible and state.truncation.threshold == 12.0
    assert field.bar.value == 12.0 and field.text.value == "12"
    field.text.value = "250"  # beyond the slider's soft end (50): the slider follows
    assert state.truncation.threshold == 250.0 and field.bar.value == 250.0
    assert field.bar.end >= 250.0


@pytest.mark.parametrize("k", (1, 2))
def test_the_phase_cursors_read_or_refuse(k):
    a = AnalysisState()
    field = NumberField(obj=a, parameter=f"cursor{k}", label=f"Cursor {k} (Hz, 0: off)")
    field.text.value = "1e5"  # above 1000 Hz
    assert field.message.visible and "Cursor" in field.message.object
    assert getattr(a, f"cursor{k}") == 0.0
    field.text.value = "25,5"
    assert getattr(a, f"cursor{k}") == 25.5 and not field.message.visible
    field.text.value = "abc"
    assert field.message.visible and getattr(a, f"cursor{k}") == 25.5
