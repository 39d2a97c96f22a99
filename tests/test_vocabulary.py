"""One word per concept: every exception in ``fbs_core.errors`` and exported, the shared
vocabulary, and the deprecated names that still work for one release (with a warning)."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import warnings

import numpy as np
import pytest

import fbs_core
from fbs_core import errors, vocabulary


def _modules():
    for info in pkgutil.walk_packages(fbs_core.__path__, "fbs_core."):
        yield importlib.import_module(info.name)


def test_every_public_exception_lives_in_errors_and_is_exported():
    found = {}
    for mod in _modules():
        for name, obj in vars(mod).items():
            if (
                inspect.isclass(obj)
                and issubclass(obj, BaseException)
                and not issubclass(obj, Warning)  # warnings are not errors
                and obj.__module__.startswith("fbs_core")
                and not name.startswith("_")
                and not mod.__name__.split(".")[-1].startswith("_")
            ):
                found[name] = obj
    assert found, "no exceptions found"
    elsewhere = {n: o.__module__ for n, o in found.items() if o.__module__ != "fbs_core.errors"}
    assert elsewhere == {}
    assert set(errors.__all__) == set(found)
    missing = [n for n in errors.__all__ if getattr(fbs_core, n, None) is not getattr(errors, n)]
    assert missing == []
    for n in errors.__all__:
        obj = getattr(errors, n)
        assert issubclass(obj, errors.FBSError) or n == "StudyCancelled", n


def test_vocabulary_values():
    assert vocabulary.DIRECTIONS == ("x", "y", "z", "rx", "ry", "rz")
    assert vocabulary.COUPLINGS == tuple(fbs_core.prediction.COUPLED_DOFS)
    assert vocabulary.HARMONIC_CASES == tuple(range(1, 8))
    # fig. 5.8's speeds are operating points of the reference tire
    for v in vocabulary.EIGEN_SPEEDS:
        assert fbs_core.reference_tire().eigenfrequencies(v).size > 0


def test_magnitude_db_and_readonly():
    x = np.array([1.0, -10.0, 1e-3j, 0.0])
    np.testing.assert_allclose(vocabulary.magnitude_db(x), [0.0, 20.0, -60.0, -600.0])
    assert vocabulary.magnitude_db(0.0, floor=None) == -np.inf
    np.testing.assert_allclose(vocabulary.magnitude_db(2.0, ref=2.0), 0.0)
    frf = fbs_core.reference_chassis().mobility([20.0, 30.0])
    np.testing.assert_allclose(frf.magnitude_db(), vocabulary.magnitude_db(frf.data, floor=None))
    a = [1.0, 2.0]
    r = vocabulary.readonly(a)
    assert not r.flags.writeable
    with pytest.raises(ValueError):
        r[0] = 3.0


def test_harmonic_case_is_a_deprecated_name_of_harmonic():
    want = fbs_core.bushing_response(2, n_modes=40)
    assert fbs_core.bushing_response(harmonic=2, n_modes=40).data.tobytes() == want.data.tobytes()
    with pytest.warns(DeprecationWarning, match="harmonic_case"):
        old = fbs_core.bushing_response(harmonic_case=2, n_modes=40)
    np.testing.assert_array_equal(old.data, want.data)
    with pytest.raises(TypeError), warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        fbs_core.bushing_response(2, harmonic_case=2)
    with pytest.raises(TypeError):
        fbs_core.bushing_response()


def test_old_couplings_mapping_warns():
    from fbs_core import prediction

    with pytest.warns(DeprecationWarning, match="COUPLED_DOFS"):
        old = prediction.COUPLINGS
    assert old is prediction.COUPLED_DOFS


# -- the words are written once: a scan of fbs_core's code (not its docstrings) ------------
def _code_of_fbs_core():
    import ast
    from pathlib import Path

    root = Path(fbs_core.__file__).parent
    for path in sorted(root.rglob("*.py")):
        if path.name != "vocabulary.py":
            yield path.relative_to(root.parent).as_posix(), ast.parse(path.read_text())


def _strings(node):
    import ast

    if isinstance(node, ast.Tuple | ast.List | ast.Set):
        return tuple(e.value for e in node.elts if isinstance(e, ast.Constant))
    return ()


def test_fbs_core_spells_the_vocabulary_only_in_vocabulary():
    """Directions, couplings, the dB conversion and the read-only copy are written in
    fbs_core/vocabulary.py and imported everywhere else in the core."""
    import ast

    found = []
    for name, tree in _code_of_fbs_core():
        for node in ast.walk(tree):
            words = _strings(node)
            if {"rx", "ry", "rz"} <= set(words) or set(words) == {"x", "y", "z"}:
                found.append(f"{name}:{node.lineno} directions (vocabulary.DIRECTIONS)")
            if {"6dof", "5dof"} <= set(words):
                found.append(f"{name}:{node.lineno} couplings (vocabulary.COUPLINGS)")
            if (
                isinstance(node, ast.BinOp)
                and isinstance(node.op, ast.Mult)
                and any(
                    isinstance(s, ast.Constant) and s.value == 20 for s in (node.left, node.right)
                )
                and "log10" in ast.unparse(node)
            ):
                found.append(f"{name}:{node.lineno} dB (vocabulary.magnitude_db)")
            if isinstance(node, ast.FunctionDef):
                body = ast.unparse(node)
                if "setflags(write=False)" in body and "copy=True" in body:
                    found.append(f"{name}:{node.lineno} read-only copy (vocabulary.readonly)")
    assert found == []


def test_couplings_and_directions_agree_everywhere():
    from fbs_core.studies._models import coupled_directions
    from fbs_core.units import input_kind, output_kind

    assert vocabulary.COUPLINGS == tuple(vocabulary.COUPLED_DIRECTIONS) == ("6dof", "5dof")
    for c, dirs in vocabulary.COUPLED_DIRECTIONS.items():
        assert coupled_directions(c) == dirs
        assert fbs_core.prediction.coupled_dofs(c) == tuple(f"hub:{d}" for d in dirs)
    # the free-rolling wheel releases its spin about the axle (y, ISO 8855) only
    assert set(vocabulary.DIRECTIONS) - set(vocabulary.COUPLED_DIRECTIONS["5dof"]) == {"ry"}
    assert vocabulary.TRANSLATIONS + vocabulary.ROTATIONS == vocabulary.DIRECTIONS
    for d in vocabulary.DIRECTIONS:
        rot = d in vocabulary.ROTATIONS
        assert output_kind(f"n:{d}") == ("rotation" if rot else "translation")
        assert input_kind(f"n:{d}") == ("moment" if rot else "force")
    assert fbs_core.dofs.DIRECTIONS is vocabulary.DIRECTIONS
