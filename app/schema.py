"""The settings schema: every setting declared once, on its parameter.

A setting of the dashboard is a parameter of a state class with ``metadata=setting(...)``:
its group (the class it belongs to), type, bounds and choices are the parameter's own; the
metadata add its URL key, the label of the report's settings table, its name in a
:class:`~app.results.Snapshot` and whether it acts only in vehicle scope. Everything else
a setting appears in is derived here from those declarations:

- the URL keys of each group (:attr:`Schema.url_keys`), read and written by the page's link;
- the snapshot's fields (:attr:`Schema.fields`, :meth:`Schema.snapshot_class`) with the
  type each value is converted to;
- the report's settings table (:attr:`Schema.report_keys`, :attr:`Schema.choices`);
- the fields that act only on the car (:attr:`Schema.vehicle_fields`).

So adding a setting is one declaration: a parameter with its metadata (``tests/
test_settings_schema.py`` adds one and follows it into the link, the snapshot and the
report). Nothing here knows the dashboard's classes; :data:`app.state.SCHEMA` is the
dashboard's schema.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import param

__all__ = ["Schema", "Setting", "setting", "url_keys_of"]

_KEY = "setting"


def setting(
    url: str | None = None,
    label: str | None = None,
    *,
    field: str | None = None,
    vehicle: bool = False,
) -> dict[str, Any]:
    """The metadata that make a parameter a setting (pass as ``metadata=``).

    Parameters
    ----------
    url : str or None
        Key of the setting in the page's link (None: not in the link, e.g. the session's
        uploaded models, which travel as digests of their own).
    label : str or None
        Its meaning in the report's settings table (None: not in the table).
    field : str or None
        Its name in a snapshot when the parameter's name is taken by another group's
        setting (default: the parameter's name).
    vehicle : bool
        Acts only in vehicle scope (a corner's results are not made of it, the report
        shows it only for the car).
    """
    return {_KEY: {"url": url, "label": label, "field": field, "vehicle": vehicle}}


def _kind(p: param.Parameter) -> type:
    """The plain type a parameter's value is held as in a snapshot (object: as it is)."""
    if isinstance(p, param.Boolean):
        return bool
    if isinstance(p, param.Integer):
        return int
    if isinstance(p, param.Number):
        return float
    if isinstance(p, param.ListSelector):
        return tuple
    if isinstance(p, param.String):
        return str
    if isinstance(p, param.Selector) and not isinstance(p, param.ClassSelector):
        kinds = {type(o) for o in p.objects}
        if len(kinds) == 1:
            return kinds.pop()
    return object


@dataclass(frozen=True)
class Setting:
    """One declared setting.

    Attributes
    ----------
    group : str
        The state group it belongs to (``"case"``, ``"noise"``...; ``"page"`` for the
        page's layout, which is in the link but not in a snapshot).
    name : str
        The parameter's name in its group.
    owner : type
        The group's class (the parameter is ``owner.param[name]``).
    field : str or None
        Its name in a snapshot (None: a page setting, not in a snapshot).
    url, label : str or None
        Its key in the link and its label in the report (None: not there).
    vehicle : bool
        Acts only in vehicle scope.
    kind : type
        The type of its value in a snapshot (``object``: kept as it is).
    choices : tuple or None
        The allowed values of a choice of words (None: not such a setting).
    """

    group: str
    name: str
    owner: type
    field: str | None
    url: str | None
    label: str | None
    vehicle: bool
    kind: type
    choices: tuple | None

    @property
    def parameter(self) -> param.Parameter:
        return self.owner.param[self.name]

    @property
    def default(self) -> Any:
        return self.parameter.default

    def convert(self, value: Any) -> Any:
        """``value`` as a snapshot holds it."""
        return value if self.kind is object else self.kind(value)


def _settings_of(group: str, cls: type, in_snapshot: bool) -> list[Setting]:
    out = []
    for name, p in cls.param.objects("existing").items():
        meta = (p.metadata or {}).get(_KEY)
        if meta is None:
            continue
        kind = _kind(p)
        choices = (
            tuple(p.objects)
            if kind is str
            and isinstance(p, param.Selector)
            and not isinstance(p, param.ListSelector)
            else None
        )
        out.append(
            Setting(
                group=group,
                name=name,
                owner=cls,
                field=(meta["field"] or name) if in_snapshot else None,
                url=meta["url"],
                label=meta["label"],
                vehicle=meta["vehicle"],
                kind=kind,
                choices=choices,
            )
        )
    return out


class Schema:
    """The settings of state groups, and what is derived from them.

    Parameters
    ----------
    groups : mapping of str to param.Parameterized subclass
        The session's state groups (their settings are a snapshot's fields).
    page : mapping of str to param.Parameterized subclass
        Groups in the link but not in a snapshot (the page's layout).

    Raises
    ------
    ValueError
        Two settings share a URL key, a snapshot field or a report label's name.
    """

    def __init__(self, groups: Mapping[str, type], page: Mapping[str, type] | None = None):
        settings: list[Setting] = []
        for group, cls in groups.items():
            settings += _settings_of(group, cls, True)
        for group, cls in (page or {}).items():
            settings += _settings_of(group, cls, False)
        self.settings: tuple[Setting, ...] = tuple(settings)
        self.groups = dict(groups)
        self.page_groups = dict(page or {})
        for what, names in (
            ("URL key", [s.url for s in settings if s.url]),
            ("snapshot field", [s.field for s in settings if s.field]),
            ("report setting", [self._report_name(s) for s in settings if s.label]),
        ):
            seen = {n for n in names if names.count(n) > 1}
            if seen:
                raise ValueError(f"two settings declare the {what} {', '.join(sorted(seen))}")

    @staticmethod
    def _report_name(s: Setting) -> str:
        return s.field or s.name

    @property
    def url_keys(self) -> dict[str, dict[str, str]]:
        """Group -> parameter -> URL key, of the snapshot's groups (the link's settings)."""
        out: dict[str, dict[str, str]] = {g: {} for g in self.groups}
        for s in self.settings:
            if s.url and s.field is not None:
                out[s.group][s.name] = s.url
        return out

    def page_url_keys(self, group: str = "page") -> dict[str, str]:
        """Parameter -> URL key of a page group's settings."""
        return {s.name: s.url for s in self.settings if s.group == group and s.url}

    @property
    def fields(self) -> dict[str, tuple[str, str]]:
        """Snapshot field -> (group, parameter)."""
        return {s.field: (s.group, s.name) for s in self.settings if s.field}

    @property
    def vehicle_fields(self) -> tuple[str, ...]:
        """Snapshot fields that act only in vehicle scope."""
        return tuple(s.field for s in self.settings if s.field and s.vehicle)

    @property
    def report_keys(self) -> dict[str, tuple[type, str]]:
        """Report setting -> (type, label), in declaration order. A list (the car's wheels)
        is reported as its words."""
        out: dict[str, tuple[type, str]] = {}
        for s in self.settings:
            if s.label:
                kind = str if s.kind in (tuple, object) else s.kind
                out[self._report_name(s)] = (kind, s.label)
        return out

    @property
    def choices(self) -> dict[str, tuple]:
        """Report setting -> its allowed words (settings that are a choice of words)."""
        return {self._report_name(s): s.choices for s in self.settings if s.label and s.choices}

    def by_field(self, field: str) -> Setting:
        for s in self.settings:
            if s.field == field:
                return s
        raise KeyError(field)

    def snapshot_class(self, base: type, name: str = "Snapshot") -> type:
        """A frozen dataclass of one field per setting of the groups, on ``base`` (a frozen
        dataclass whose own fields have defaults: the published inputs)."""
        fields = [
            (s.field, s.kind if s.kind is not object else Any, dataclasses.field(kw_only=True))
            for s in self.settings
            if s.field
        ]
        return dataclasses.make_dataclass(
            name,
            fields,
            bases=(base,),
            frozen=True,
            namespace={"__module__": base.__module__, "__doc__": base.__doc__, "schema": self},
        )


def url_keys_of(cls: type) -> dict[str, str]:
    """Parameter -> URL key of the settings of one class (a group of the page)."""
    return Schema({}, page={"page": cls}).page_url_keys()
