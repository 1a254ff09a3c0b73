"""Random streams keyed by (seed, asset, step, purpose), so that results do not depend on batching.

A fleet monitor filters many assets in one vectorized step.  With one generator for the batch, an
asset's draws would depend on which other assets share its batch, and in which order; here every
asset has its own counter-based stream (Philox, Salmon et al. (2011)): its key comes from the
seed's child ``prognosis.seeds.spawn(seed, ASSETS, asset key)`` and the counter is set from the
filter step, the purpose of the draws (filter moves, initial rates, initial theta) and a lane (the
hypothesis), so the numbers an asset gets at a step
are a function of ``(seed, asset, step, purpose)`` alone: the same alone, in any batch, on any
worker, and after a restart (the step is all the state a stream has).

Asset identities may be integers or strings; a string is hashed (BLAKE2b) into the spawn key, so the
key of ``"motor-17"`` is the same in every process (Python's ``hash`` is salted per process).

Examples
--------
>>> streams = AssetStreams(seed=0)
>>> a = streams.normals(["pump-1", "pump-2"], step=3, size=4)
>>> b = streams.normals(["pump-2"], step=3, size=4)   # pump-2 alone: the same numbers
>>> bool(np.array_equal(a[1], b[0])), bool(np.array_equal(a[0], a[1]))
(True, False)
>>> bool(np.array_equal(streams.normals(["pump-1"], step=4, size=4)[0], a[0]))   # another step, other numbers
False
"""

from __future__ import annotations

import hashlib
import numbers
from collections.abc import Sequence

import numpy as np

from . import seeds
from .errors import PrognosisError

__all__ = ["AssetStreams", "MOVES", "RATES", "STARTS", "asset_key"]

MOVES, RATES, STARTS = 0, 1, 2  # purposes: a filter step's moves, the initial rates, the initial theta


def asset_key(asset: object) -> int:
    """A stable non-negative integer for an asset id (an int as is, a string by BLAKE2b).

    >>> asset_key(17), asset_key("motor-17") == asset_key("motor-17")
    (17, True)
    """
    if isinstance(asset, (bool, np.bool_)):
        raise TypeError(f"asset ids are integers or strings, got the bool {asset!r}")
    if isinstance(asset, numbers.Integral):
        if asset < 0:
            raise PrognosisError(f"asset id {asset} is negative; integer asset ids must be >= 0")
        return int(asset)
    if isinstance(asset, str):
        # the top bit marks a hashed string, so the string "17" and the integer 17 get different keys
        return int.from_bytes(hashlib.blake2b(asset.encode(), digest_size=8).digest(), "little") | (1 << 64)
    raise TypeError(f"asset ids are integers or strings, got the {type(asset).__name__} {asset!r}")


class AssetStreams:
    """Counter-based streams, one per asset, positioned by (step, purpose).

    Parameters
    ----------
    seed : int
        The fleet's seed (``SeedSequence`` entropy).

    Notes
    -----
    Each call positions one Philox generator per asset (about a microsecond) and draws that asset's
    numbers for the step in one call, so the cost per number is numpy's.  The draws of one
    (asset, step, purpose) must always be requested in the same sizes and order by the caller.
    """

    def __init__(self, seed: int = 0):
        if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, numbers.Integral) or seed < 0:
            raise PrognosisError(f"seed must be a whole number >= 0, got {seed!r}")
        self.seed = int(seed)
        self._keys: dict = {}
        self._bits = np.random.Philox(0)
        self._generator = np.random.Generator(self._bits)
        self._state = self._bits.state

    def __getstate__(self) -> dict:
        return {"seed": self.seed}

    def __setstate__(self, state: dict) -> None:
        self.__init__(state["seed"])

    def key(self, asset: object) -> np.ndarray:
        """The Philox key (2 x uint64) of an asset."""
        key = self._keys.get(asset)
        if key is None:
            sequence = seeds.spawn(self.seed, seeds.ASSETS, asset_key(asset))
            key = self._keys[asset] = sequence.generate_state(2, np.uint64)
        return key

    def generator(self, asset: object, step: int, purpose: int = MOVES, lane: int = 0) -> np.random.Generator:
        """A generator at the start of the stream of ``(asset, step, purpose, lane)``.

        ``lane`` tells apart streams of one asset at one step (the fleet's hypotheses).  The
        generator object is shared: use it before the next call.
        """
        state = self._state
        state["state"]["key"] = self.key(asset)
        state["state"]["counter"] = np.array([0, int(step), int(purpose), int(lane)], np.uint64)
        state["buffer_pos"], state["has_uint32"] = 4, 0  # no number left over from another stream
        self._bits.state = state
        return self._generator

    def normals(self, assets: Sequence, step, size: int, purpose: int = MOVES,
                out: np.ndarray | None = None) -> np.ndarray:
        """Standard normals ``(len(assets), size)``, row ``i`` from the stream of ``assets[i]``.

        ``step`` is one step for all, or one per asset.
        """
        steps = np.broadcast_to(np.asarray(step), (len(assets),))
        out = np.empty((len(assets), size)) if out is None else out
        for row, (asset, k) in enumerate(zip(assets, steps)):
            self.generator(asset, k, purpose).standard_normal(out=out[row])
        return out

    def uniforms(self, assets: Sequence, step, size: int, purpose: int = MOVES) -> np.ndarray:
        """Uniforms on [0, 1) ``(len(assets), size)``, row ``i`` from the stream of ``assets[i]``."""
        steps = np.broadcast_to(np.asarray(step), (len(assets),))
        out = np.empty((len(assets), size))
        for row, (asset, k) in enumerate(zip(assets, steps)):
            self.generator(asset, k, purpose).random(out=out[row])
        return out
