"""The one link of widgets and state, the page's link and the view ids, without a browser."""

from __future__ import annotations

import urllib.parse

import panel as pn
from panel.io.location import Location

from app.main import sync_url
from app.page.titles import VIEW_ID_KEY, ViewLinks, short_link, state_query
from app.results.base import Snapshot
from app.state import DashboardState
from app.views.bind import Binder, control
from app.views.controls import Controls


def test_every_control_shows_the_state_whichever_side_changes():
    s = DashboardState()
    c = Controls(state=s)
    w = c.widgets()
    w["case.n_modes"].value = 120  # the user
    assert s.case.n_modes == 120
    s.case.n_modes = 70  # a link, a pin, another control
    assert w["case.n_modes"].value == 70
    s.case.wheels = ["rl"]
    assert w["case.wheels"].value == ["rl"]
    f = c.fields["noise.noise"]
    f.text.value = "abc"  # refused: the message, and the field shows the value in force
    assert s.noise.noise == 10.0 and f.text.value == "10" and f.message.visible
    f.text.value = "5,5"
    assert s.noise.noise == 5.5 and f.bar.value == 5.5 and not f.message.visible
    f.bar.value = 3.0
    assert f.text.value == "3"
    binder = Binder.of(None)
    assert binder.mismatches() == []


def test_a_refused_widget_value_changes_nothing():
    s = DashboardState()
    messages = []
    slider = control(pn.widgets.IntSlider, s.case.param.harmonic, refused=messages.append)
    slider.value = 9  # outside 1-7: param refuses it
    assert s.case.harmonic == 1 and slider.value == 1
    assert messages and "harmonic" in messages[0].lower()


def test_the_url_and_the_title_links_are_one_function_of_the_state():
    s = DashboardState()
    s.case.param.update(harmonic=4, scope="vehicle", wheels=["fr", "rl"], n_modes=120)
    q = state_query(s)
    assert q == state_query(Snapshot.of(s))  # the page's state and a result's snapshot
    assert q["h"] == "4" and q["scope"] == "vehicle" and "dof" not in q  # defaults dropped
    other = DashboardState()
    sync_url(other, Location(search="?" + urllib.parse.urlencode(q)))
    assert (other.case.harmonic, other.case.scope, other.case.wheels, other.case.n_modes) == (
        4,
        "vehicle",
        ["fr", "rl"],
        120,
    )


def test_a_number_has_one_spelling_whether_dragged_or_typed():
    # a slider sends a whole number as an int (JSON 36), a typed field as a float (36.0): one
    # setting, so the URL and a view id's snapshot must write it the same (the random walk
    # found a title link "thr=36.0" under a page URL "thr=36")
    dragged, typed = DashboardState(), DashboardState()
    dragged.truncation.threshold = 36
    typed.truncation.threshold = 36.0
    assert state_query(dragged) == state_query(typed) == state_query(Snapshot.of(dragged))
    c = Controls(state=DashboardState())
    bar = c.fields["truncation.threshold"].bar
    bar.value = 36  # the browser's JSON number
    assert type(c.state.truncation.threshold) is float


def test_a_long_link_is_a_view_id_that_opens_its_state_and_the_table_is_bounded():
    links = ViewLinks(max_entries=3, max_chars=400)
    s = DashboardState()
    s.case.param.update(harmonic=5, n_modes=150, dof="rx", coupling="5dof", wheels=["fl"])
    s.noise.param.update(noise=5.5, seed=3, rounds=800)
    q = state_query(s)
    link = short_link("http://host:5006/main", q, links)
    assert len(link) <= 72 and f"?{VIEW_ID_KEY}=" in link
    opened = DashboardState()
    loc = Location(search="?" + urllib.parse.urlsplit(link).query + "&view=present")
    from app.page import titles
    from app.page.layout import PageState

    page = PageState()
    assert titles.resolve_view_id(loc, links) is None  # (the page reads the server's table)
    sync_url(opened, loc, page=page)
    assert state_query(opened) == q and page.view == "present"
    for k in range(5):  # at most max_entries kept, the oldest dropped
        links.add(f"h={k}")
    assert len(links) == 3 and links.get(ViewLinks.id_of("h=0")) is None
    assert links.add("x" * 401) is None  # too long to keep: the whole link is written
    # an unknown id opens the link's other keys
    unknown = Location(search="?v=zzzzzzzzzz&N=60")
    assert titles.resolve_view_id(unknown, links) == "zzzzzzzzzz"
    assert unknown.search == "?N=60"
