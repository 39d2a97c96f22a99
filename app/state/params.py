"""Parameters of the page state that take numbers, never booleans.

``param.Number`` and ``param.Integer`` accept ``True``/``False`` (a bool is an int in
Python), and Panel reads a link's ``?noise=true`` as the boolean ``True``: the state then
held ``True`` and the page's number field refused it while the page was built, a blank page
(found by the URL fuzz tests). These refuse booleans with param's usual ``ValueError``, so a link's
boolean is ignored like any other value out of range.
"""

from __future__ import annotations

from typing import Any

import param

__all__ = ["Integer", "Number"]


def _no_bool(p: param.Parameter, value: Any) -> None:
    if isinstance(value, bool):
        raise ValueError(f"{p.owner.__name__}.{p.name} takes a number, not {value!r}")


class Number(param.Number):
    """``param.Number`` that refuses booleans."""

    def _validate_value(self, value: Any, allow_None: bool) -> None:
        _no_bool(self, value)
        super()._validate_value(value, allow_None)


class Integer(param.Integer):
    """``param.Integer`` that refuses booleans."""

    def _validate_value(self, value: Any, allow_None: bool) -> None:
        _no_bool(self, value)
        super()._validate_value(value, allow_None)
