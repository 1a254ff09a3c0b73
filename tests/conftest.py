"""A guard for doctest's linecache sweep (scenarios for the unit tests: tests/scenarios.py)."""

import functools
import gc
import linecache


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
