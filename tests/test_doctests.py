"""The Examples in fbs_core's docstrings run and print what they say (doctest).

Every module of the package is imported and its docstrings' examples executed; an
example marked ``# doctest: +SKIP`` (one that needs minutes or the whole reference
study) is skipped. A stray line or a changed result fails here.
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import fbs_core

MODULES = sorted(
    m.name
    for m in pkgutil.walk_packages(fbs_core.__path__, "fbs_core.")
    if not m.name.endswith("__main__")
)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name, capsys):
    mod = importlib.import_module(name)
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    result = doctest.testmod(mod, optionflags=flags, report=False)
    out = capsys.readouterr().out
    assert result.failed == 0, out
