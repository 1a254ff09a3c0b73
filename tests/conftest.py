"""Shared fixtures: the example scripts loaded as modules; a guard for doctest's linecache sweep."""

import functools
import gc
import importlib.util
import linecache
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _without_cyclic_gc(checkcache):
    """``linecache.checkcache`` with the cyclic garbage collector paused while it sweeps the cache.

    sympy's lambdify removes a generated function's source from ``linecache.cache`` in a finalizer; when a
    collection runs that finalizer in the middle of the sweep, the sweep raises ``KeyError:
    '<lambdifygenerated-N>'`` (CPython gh-126775).  Doctest sweeps at the start of every run, so the
    tutorials and ``--doctest-modules`` failed now and then.  This conftest is imported at collection,
    before any test runs.
    """
    @functools.wraps(checkcache)
    def sweep(filename=None):
        paused = gc.isenabled()
        gc.disable()
        try:
            return checkcache(filename)
        finally:
            if paused:
                gc.enable()
    return sweep


linecache.checkcache = _without_cyclic_gc(linecache.checkcache)


def load_example(name: str):
    """Import ``examples/<name>.py`` (registered in sys.modules: dataclasses look their module up)."""
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def example():
    """examples/torsion_bar.py, the main job."""
    return load_example("torsion_bar")
