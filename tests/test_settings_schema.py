"""Every setting is declared once (its parameter's ``metadata=setting(...)``); the link, the
snapshot, the report's settings table and the vehicle-only fields follow from it.

The truth here is the declaration itself: a setting added in one line (a parameter of a
subclass) must appear, with its type, key and label, everywhere a setting appears, and every
parameter of the session's state must be such a declaration (a parameter added without one
would be a control the link, the snapshot or the report forget).
"""

from __future__ import annotations

import dataclasses
import urllib.parse

import param
import pytest

from app.page import titles
from app.page.layout import PAGE_URL_KEYS, PageState
from app.report import data as report_data
from app.report.session import settings_of
from app.results import FIELDS, Snapshot
from app.results.base import VEHICLE_FIELDS, _SnapshotBase
from app.schema import Schema, setting
from app.state import SCHEMA, URL_KEYS, DashboardState, NoiseState
from app.state.params import Number


class _WobblyNoise(NoiseState):
    wobble = Number(default=0.25, bounds=(0.0, 1.0), metadata=setting("wob", "road wobble"))


def _schema_with_wobble() -> Schema:
    return Schema({**SCHEMA.groups, "noise": _WobblyNoise}, page=SCHEMA.page_groups)


def test_a_new_setting_is_one_declaration():
    schema = _schema_with_wobble()
    assert schema.url_keys["noise"]["wobble"] == "wob"
    assert schema.fields["wobble"] == ("noise", "wobble")
    assert schema.report_keys["wobble"] == (float, "road wobble")
    assert "wobble" not in schema.vehicle_fields
    # the snapshot holds it as its declared type
    snap_cls = schema.snapshot_class(_SnapshotBase)
    state = DashboardState(noise=_WobblyNoise(wobble=1))
    snap = snap_cls.of(state)
    assert snap.wobble == 1.0 and type(snap.wobble) is float
    assert snap.replace(wobble=0.5) != snap and snap.replace(wobble=1.0) == snap
    # the link writes it when it differs from its default, and from a snapshot alike
    q = titles.state_query(state, schema=schema)
    assert q["wob"] == "1.0"
    assert titles.state_query(snap, schema=schema) == q
    assert "wob" not in titles.state_query(DashboardState(noise=_WobblyNoise()), schema=schema)
    # the app's own schema does not know it
    assert "wobble" not in FIELDS and "wobble" not in report_data.SETTING_KEYS


def test_every_parameter_of_the_state_is_a_declared_setting():
    declared = {(s.group, s.name) for s in SCHEMA.settings}
    for group, cls in {**SCHEMA.groups, **SCHEMA.page_groups}.items():
        for name in cls.param:
            if name == "name":
                continue
            assert (group, name) in declared, f"{cls.__name__}.{name} has no setting(...)"


def test_what_is_derived_is_the_app_s_own_tables():
    assert URL_KEYS == SCHEMA.url_keys and PAGE_URL_KEYS == SCHEMA.page_url_keys()
    assert FIELDS == SCHEMA.fields and VEHICLE_FIELDS == SCHEMA.vehicle_fields
    assert report_data.SETTING_KEYS == SCHEMA.report_keys
    snap_fields = {f.name for f in dataclasses.fields(Snapshot)} - {"band", "pins"}
    assert snap_fields == set(SCHEMA.fields)
    assert set(VEHICLE_FIELDS) == {"wheels", "tracks", "coherence", "point"}
    # every setting a snapshot holds in the link has one key, and the keys are distinct
    keys = [s.url for s in SCHEMA.settings if s.url]
    assert len(keys) == len(set(keys))


def test_a_schema_refuses_two_settings_with_one_key():
    class Twice(param.Parameterized):
        a = param.Boolean(False, metadata=setting("k"))
        b = param.Boolean(False, metadata=setting("k"))

    with pytest.raises(ValueError, match="URL key k"):
        Schema({"twice": Twice})


def _other_value(s, state):
    """A valid value of setting ``s`` other than its default."""
    p = s.parameter
    d = s.default
    if isinstance(p, param.Boolean):
        return not d
    if isinstance(p, param.ListSelector):
        return list(p.objects[:1]) if list(d) != list(p.objects[:1]) else list(p.objects[1:2])
    if isinstance(p, param.Selector) and not isinstance(p, param.ClassSelector):
        return next(o for o in p.objects if o != d)
    if isinstance(p, param.Integer):
        lo, hi = p.bounds
        return d + 1 if hi is None or d + 1 <= hi else d - 1
    if isinstance(p, param.Number):
        lo, hi = p.bounds
        v = d + 0.25
        return v if hi is None or v <= hi else d - 0.25
    raise AssertionError(f"no other value known for {s.name}")


#: Settings of free text (pins, a compared run, the page's uploads and review) have values
#: with checks of their own (tests/test_app_pins.py, test_app_review.py...).
_CHOSEN = [s for s in SCHEMA.settings if s.url and not isinstance(s.parameter, param.String)]


@pytest.mark.parametrize("setting_", _CHOSEN, ids=lambda s: s.url)
def test_each_linked_setting_goes_into_the_link_and_comes_back(setting_):
    """A setting moved off its default is written in the link by its declared key and read
    back from that link into a fresh session (the page's own reader)."""
    from app.page.titles import read_link

    state = DashboardState()
    value = _other_value(setting_, state)
    if setting_.field is None:
        page = PageState()
        setattr(page, setting_.name, value)
        layout = {setting_.url: getattr(page, setting_.name)}
        q = titles.state_query(state, layout)
        assert q == {setting_.url: q[setting_.url]}
        fresh_page = PageState()
        read_link(_Location(q), fresh_page, PAGE_URL_KEYS)
        assert getattr(fresh_page, setting_.name) == getattr(page, setting_.name)
        return
    obj = getattr(state, setting_.group)
    setattr(obj, setting_.name, value)
    q = titles.state_query(state)
    assert setting_.url in q, q
    fresh = DashboardState()
    fresh_obj = getattr(fresh, setting_.group)
    read_link(_Location(q), fresh_obj, URL_KEYS[setting_.group])
    assert getattr(fresh_obj, setting_.name) == getattr(obj, setting_.name)
    assert Snapshot.of(fresh).replace(band=None) == Snapshot.of(state).replace(band=None)


class _Location:
    """The part of Panel's location the page's link reader uses: the query of a link."""

    def __init__(self, query):
        from panel.util import parse_query

        self.search = "?" + urllib.parse.urlencode(query)
        self.query_params = parse_query(self.search)


def test_the_report_shows_the_car_s_settings_only_in_vehicle_scope():
    corner = settings_of(Snapshot.of(DashboardState()))
    assert not set(VEHICLE_FIELDS) & set(corner)
    car = DashboardState()
    car.case.scope = "vehicle"
    shown = settings_of(Snapshot.of(car))
    assert {"wheels", "tracks", "point"} <= set(shown)
    assert list(shown) == [k for k in report_data.SETTING_KEYS if k in shown]
