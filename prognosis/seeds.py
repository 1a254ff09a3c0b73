"""Independent random streams from one seed: one per consumer, none shared between seeds.

A monitor draws random numbers for several purposes (the particle filter's moves and resampling,
the RUL predictor's noise bank and its per-prediction permutations, the prior of the rates).  Each
purpose is a *consumer* and gets its own stream, a child of the seed's
:class:`numpy.random.SeedSequence` named by a spawn key: ``spawn(seed, FILTER)`` is what
``SeedSequence(seed).spawn(FILTER + 1)[FILTER]`` returns, without the parent's spawn counter, so a
stream depends on its key alone and not on what was spawned before.

Deriving streams by arithmetic on the seed (``seed + 1`` for the RUL, ``[seed, key]`` for a
prediction) makes seeds overlap: the RUL of seed ``s`` then drew the filter noise of seed ``s + 1``,
and ``default_rng([s, 0])`` is ``default_rng(s)``, since a SeedSequence pads its entropy with zeros.
A spawn key is hashed apart from the entropy, so ``spawn(s, i)`` and ``spawn(s + 1, j)`` differ for
every ``i``, ``j``.

>>> import numpy as np
>>> a, b = generator(0, RUL).random(), generator(1, FILTER).random()
>>> a != b, generator(0, RUL).random() == a     # independent, and reproducible
(True, True)
>>> child = np.random.SeedSequence(0).spawn(1)[0]     # the same stream as numpy's spawn
>>> bool(np.array_equal(spawn(0, FILTER).generate_state(4), child.generate_state(4)))
True
"""

from __future__ import annotations

import numbers

import numpy as np

from .errors import PrognosisError

__all__ = ["ASSETS", "FILTER", "PREDICTORS", "RATE_PRIOR", "RESOLUTION", "RUL", "check_seed", "generator", "spawn"]

#: Spawn keys of a monitor's consumers (the first element of the key under the monitor's seed).
FILTER = 0  # the particle filter: initial particles, moves, resampling
RUL = 1  # the RUL predictor of a HealthMonitor
RATE_PRIOR = 2  # the initial rate particles of an IsolatingMonitor's hypotheses
PREDICTORS = 3  # an IsolatingMonitor's RUL predictors, one per hypothesis row: key (PREDICTORS, row)
ASSETS = 4  # a fleet's per-asset streams (prognosis.random_streams): key (ASSETS, asset key)
RESOLUTION = 5  # an IsolatingMonitor's spread of a RUL over the filter step: key (RESOLUTION, prediction)


def check_seed(seed: object, option: str = "seed") -> int | np.random.SeedSequence:
    """``seed`` if a whole number >= 0 or a SeedSequence; otherwise a PrognosisError naming ``option``.

    >>> check_seed(7)
    7
    >>> check_seed(-1)
    Traceback (most recent call last):
    ...
    prognosis.errors.PrognosisError: seed must be a whole number >= 0 or a numpy.random.SeedSequence, got -1
    """
    if isinstance(seed, np.random.SeedSequence):
        return seed
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise PrognosisError(f"{option} must be a whole number >= 0 or a numpy.random.SeedSequence, got {seed!r}")
    return int(seed)


def spawn(seed: int | np.random.SeedSequence, *key: int) -> np.random.SeedSequence:
    """The child of ``seed`` under spawn key ``key`` (appended to the key ``seed`` already has).

    ``spawn(spawn(s, 1), 2) == spawn(s, 1, 2)``: a consumer can derive streams of its own from the
    sequence it was given.

    >>> spawn(5, 1, 2).spawn_key, spawn(spawn(5, 1), 2).spawn_key
    ((1, 2), (1, 2))
    >>> bool(generator(spawn(5, 1), 2).random() == generator(5, 1, 2).random())
    True
    """
    parent = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(check_seed(seed))
    return np.random.SeedSequence(parent.entropy, spawn_key=(*parent.spawn_key, *map(int, key)),
                                  pool_size=parent.pool_size)


def generator(seed: int | np.random.SeedSequence, *key: int) -> np.random.Generator:
    """A fresh :func:`numpy.random.default_rng` on the stream ``spawn(seed, *key)``.

    >>> first = generator(3, 0).random()
    >>> bool(generator(3, 0).random() == first), bool(generator(3, 1).random() == first)
    (True, False)
    """
    return np.random.default_rng(spawn(seed, *key))
