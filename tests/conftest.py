"""A guard for doctest's linecache sweep, and the ``extras`` marker of the doctests and tests that need an
optional package (scenarios for the unit tests: tests/scenarios.py)."""

import functools
import gc
import linecache

import pytest

#: Doctests that need a package of an optional extra, by doctest name -> the package.  With the interop
#: tests and the test files marked ``extras``, they are what ``pip install .`` alone cannot run:
#: ``pytest -m "not extras"`` is the core's suite.
EXTRA_DOCTESTS = {
    "bondgraph.simulation.SimulationResult.to_frame": "pandas",
    "diagnosis.detection.Evaluation.to_frame": "pandas",
    "prognosis.health_monitor.MonitorResult.rul_frame": "pandas",
    "prognosis.health_monitor.MonitorResult.to_frame": "pandas",
    "bgphm.fleet.engine.run_fleet": "pyarrow",
    "bgphm.fleet.sources.ParquetRecords.selection": "pyarrow",
    "bgphm.plotting": "matplotlib",
}


def pytest_collection_modifyitems(config, items):
    """Mark ``extras`` every interop test, every browser test (playwright) and every doctest of
    :data:`EXTRA_DOCTESTS`."""
    for item in items:
        browser = item.nodeid.startswith("tests/browser/")
        if item.get_closest_marker("interop") or item.name in EXTRA_DOCTESTS or browser:
            item.add_marker(pytest.mark.extras)


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
