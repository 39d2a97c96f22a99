"""Every public name of fbs_core is documented (in the spirit of python-control's
``control/tests/docstrings_test.py``): a docstring exists, and every parameter of
a public function or class constructor is named in it."""

from __future__ import annotations

import inspect

import pytest

import fbs_core

PUBLIC = [n for n in fbs_core.__all__ if callable(getattr(fbs_core, n))]


@pytest.mark.parametrize("name", PUBLIC)
def test_public_callable_is_documented(name):
    obj = getattr(fbs_core, name)
    doc = inspect.getdoc(obj)
    assert doc and len(doc.strip()) > 20, f"fbs_core.{name} has no docstring"
    if inspect.isclass(obj) and issubclass(obj, BaseException):
        return
    target = obj.__init__ if inspect.isclass(obj) else obj
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return
    missing = [
        p
        for p in sig.parameters
        if p not in ("self", "cls")
        and not p.startswith("_")
        and sig.parameters[p].kind
        not in (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)
        and p not in doc
    ]
    assert not missing, f"fbs_core.{name}: parameters {missing} are not described in its docstring"
