"""Every public name of fbs_core.analysis is documented, with all its parameters named
(the check of tests/test_docstrings.py, applied to the analysis package)."""

import inspect

import pytest

import fbs_core.analysis as an

PUBLIC = [n for n in an.__all__ if callable(getattr(an, n))]


@pytest.mark.parametrize("name", PUBLIC)
def test_public_callable_is_documented(name):
    obj = getattr(an, name)
    doc = inspect.getdoc(obj)
    assert doc and len(doc.strip()) > 20, f"fbs_core.analysis.{name} has no docstring"
    target = obj.__init__ if inspect.isclass(obj) else obj
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return
    missing = [
        p
        for p in sig.parameters
        if p not in ("self", "cls")
        and sig.parameters[p].kind
        not in (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)
        and p not in doc
    ]
    assert not missing, f"fbs_core.analysis.{name}: parameters {missing} not in its docstring"


def test_thesis_equations_are_cited():
    """The modules that implement thesis equations say which."""
    import fbs_core.analysis.contributions as c
    import fbs_core.analysis.peaks as p
    import fbs_core.analysis.speedmap as s

    assert "eq. 4.1" in c.__doc__ and "eq. 4.1" in s.__doc__ and "eq. 2.2" in p.__doc__
