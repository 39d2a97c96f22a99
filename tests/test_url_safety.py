"""Values of a link are checked and shown as text (issue 28, findings 2 and 5).

- every field of a pin in the link is checked against the values the page's controls allow
  (``decode_pins``), with a message naming the pin, the field and what is allowed, so a
  crafted pin gives a message, never an error while the page is built;
- a message or notice that repeats a value of the link holds no markup.

Every URL key a page reads holding hostile values: tests/test_url_fuzz.py (in process) and
tests/browser/test_server_attacks.py (served as the Docker image serves it, and in chromium).
"""

from __future__ import annotations

import html

import pytest

from app.page.chrome import link_notice, link_notice_html
from app.report import Provenance
from app.state.pins import PinSettings, decode_pins, encode_pins, shown
from fbs_core.errors import FBSError

GOOD = PinSettings("base", 2, 60, "z", "6dof", False, 10.0, "both", False, 1000, 7, 90, "reference")
LINK = encode_pins([GOOD])
MARKUP = "<img src=x onerror=alert(1)>"


def test_a_valid_pin_round_trips():
    assert decode_pins(LINK) == (GOOD,)
    key = "tire=0123456789abcdef;chassis=reference"
    upload = PinSettings("up", 1, 10, "rx", "5dof", True, 0.0, "tire", True, 1, 0, 50, key)
    assert decode_pins(encode_pins([GOOD, upload])) == (GOOD, upload)


@pytest.mark.parametrize(
    ("field", "old", "new", "allowed"),
    [
        ("harmonic", "h2", "h99", "1 to 7"),
        ("harmonic", "h2", "h0", "1 to 7"),
        ("n_modes", "N60", "N-5", "10, 20, ..., 400"),
        ("n_modes", "N60", "N65", "10, 20, ..., 400"),
        ("dof", "dz", "dq", "x, y, z, rx, ry, rz"),
        ("coupling", "c6dof", "c7dof", "6dof, 5dof"),
        ("noise", "p10", "pnan", "0 to 99.99"),
        ("noise", "p10", "p100", "0 to 99.99"),
        ("noise", "p10", "p-1", "0 to 99.99"),
        ("target", "tboth", "twheel", "both, tire, chassis"),
        ("residual", "r0", "r2", "0 or 1"),
        ("frequency_dependent", "f0", "f2", "0 or 1"),
        ("rounds", "R1000", "R0", "1 to 200000"),
        ("rounds", "R1000", "R1e9", "1 to 200000"),
        ("seed", "s7", "s-1", "0 to 4.29497e+09"),
        ("percentile", "q90", "q91", "50, 80, 90, 95, 99"),
        ("models", "mreference", "m" + MARKUP, "reference or an upload's key"),
    ],
)
def test_every_field_of_a_pin_is_checked(field, old, new, allowed):
    assert old in LINK
    with pytest.raises(FBSError) as err:
        decode_pins(LINK.replace(old, new))
    msg = str(err.value)
    assert "pin 'base'" in msg and field in msg and allowed in msg
    assert "<" not in msg and ">" not in msg


@pytest.mark.parametrize(
    ("link", "match"),
    [
        (LINK + "~h3", "harmonic given twice"),
        (LINK.replace("~s7", ""), "lacks seed"),
        (LINK + "~z1", "unknown field"),
        (LINK + "~", "unknown field"),
        (f"{MARKUP}~h1", "a pin name has"),
        ("|".join([LINK.replace("base", f"p{k}") for k in range(9)]), "at most 8"),
    ],
)
def test_malformed_pins_are_refused_with_a_plain_text_message(link, match):
    with pytest.raises(FBSError, match=match) as err:
        decode_pins(link)
    assert "<" not in str(err.value)


def test_shown_values_are_plain_text_and_short():
    assert shown(MARKUP) == "'\\x3cimg src=x onerror=alert\\x281\\x29\\x3e'"
    assert shown("a" * 500).endswith("...'") and len(shown("a" * 500)) < 90
    inner = shown("[x](javascript:1)\"'&")[1:-1]
    assert html.escape(inner) == inner


def test_a_crafted_pin_gives_a_message_in_the_analysis_card():
    from app.state import DashboardState
    from app.store import Results

    for link in (LINK.replace("h2", "h99"), LINK.replace("dz", "dq"), LINK.replace("N60", "N-5")):
        state = DashboardState()
        state.analysis.pins = link  # the link's values, then the store: as the page is built
        r = Results(state=state)  # no exception
        assert "malformed pin" in r.message and r.pins == ()


@pytest.mark.parametrize(
    "value",
    [
        MARKUP,
        "tire:" + MARKUP,
        "chassis:[x](http://attacker.example/x)",
        "tire:![i](http://attacker.example/i.png)",
        "x" * 5000,
    ],
)
def test_the_link_notice_repeats_the_value_as_text(value):
    text = link_notice(value, Provenance())
    assert text and len(text) < 500
    out = link_notice_html(text)
    head, tail = '<div class="alert alert-warning" role="alert">', "</div>"
    assert out.startswith(head) and out.endswith(tail)
    inner = out[len(head) : -len(tail)]
    # no markup of the value: the page shows exactly the notice's text
    assert "<" not in inner and ">" not in inner and html.unescape(inner) == text


def test_a_boolean_in_the_link_is_no_number():
    """``?noise=true`` reached the state as ``True`` (param takes a bool for a number) and
    the page's number field refused it while the page was built: a blank page."""
    from panel.io.location import Location

    from app.main import sync_url
    from app.state import DashboardState

    s = DashboardState()
    query = "?noise=true&rounds=true&h=true&seed=false&thr=true&fmax=true&c1=true&N=150"
    sync_url(s, Location(search=query))
    assert (s.noise.noise, s.noise.rounds, s.case.harmonic, s.noise.seed) == (10.0, 10_000, 1, 0)
    assert (s.truncation.threshold, s.truncation.f_max, s.analysis.cursor1) == (20.0, 160.0, 0.0)
    assert s.case.n_modes == 150  # the valid value after them is kept
    for v in (s.noise.noise, s.noise.rounds, s.case.harmonic, s.truncation.threshold):
        assert not isinstance(v, bool)


def test_the_page_url_of_a_crafted_address_is_a_valid_report_link(monkeypatch):
    """The page's URL goes into every title block and report; a quote or an angle bracket in
    the path or the fragment (which browsers leave unencoded) made the report refuse it."""
    import panel as pn

    from app.page.titles import page_url
    from app.report.data import ReportData

    class Loc:  # what page_url reads of Panel's Location
        href = "http://h:5006/main'x<y>?h=3#'frag\""
        query_params = {"h": 3, "dof": "<b>"}

    loc = Loc()
    monkeypatch.setattr(type(pn.state), "location", property(lambda self: loc))
    url = page_url()
    assert url.startswith("http://h:5006/main%27x%3Cy%3E") and "#" not in url
    assert not any(c in url for c in "\"'<> ")
    settings = {"harmonic": 3, "n_modes": 50, "dof": "z", "coupling": "6dof"}
    assert ReportData(settings=settings, url=url).url == url  # accepted by the report
