"""Results remembered by the content of a model, so that a symbolic derivation is paid once per model.

Deriving state equations or ARRs with sympy takes from milliseconds to seconds; a parameter sweep, a
notebook re-run or a fleet of assets on one model asks for the same derivation again and again.  A
:class:`ContentCache` keys a result by :func:`content_key` of what it depends on (the model's elements,
laws, values and bonds, and the options), never by the identity of a Python object: a model edited
since is a different key, and two models built alike share one entry.

Examples
--------
>>> from bondgraph.library import rlc_circuit
>>> content_key(rlc_circuit().structure()) == content_key(rlc_circuit().structure())
True
>>> content_key({"R": 1}) == content_key({"R": 1.0})   # equal to Python, not to a model
False
>>> cache = ContentCache(2)
>>> cache.get(content_key("R"), lambda: 10.0), cache.get(content_key("R"), lambda: 99.0)
(10.0, 10.0)
"""

from __future__ import annotations

import dataclasses
import warnings
from collections import OrderedDict
from collections.abc import Callable, Hashable, Mapping

__all__ = ["ContentCache", "content_key"]


def content_key(value: object) -> Hashable | None:
    """A hashable image of ``value`` that is equal only for equal content, types and order included.

    Dataclasses, mappings, sequences and sets are followed; other values (str, numbers, sympy
    expressions) stand for themselves with their type.  None when something inside cannot be hashed
    (say an array as a value): such a value is not remembered.
    """
    key = _image(value)
    try:
        hash(key)
    except TypeError:
        return None
    return key


def _image(value: object) -> object:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return (type(value).__name__, *(_image(getattr(value, f.name)) for f in dataclasses.fields(value)))
    if isinstance(value, Mapping):
        return ("mapping", *((_image(k), _image(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple)):
        return (type(value).__name__, *(_image(v) for v in value))
    if isinstance(value, (set, frozenset)):
        return frozenset(_image(v) for v in value)
    return (type(value).__name__, value)   # 1, 1.0 and True are equal to Python, not to a model


class ContentCache:
    """The results of the last ``size`` keys; the least recently asked for is forgotten first.

    The warnings a computation gave are given again each time its result is asked for, so a remembered
    result says what a fresh one would.  A failed computation is not remembered.  Callers that hand out
    mutable results hand out copies.
    """

    def __init__(self, size: int) -> None:
        self.size = size
        self._entries: OrderedDict = OrderedDict()

    def get(self, key: Hashable | None, compute: Callable[[], object]) -> object:
        """The result for ``key``, computed by ``compute()`` the first time (every time if ``key`` is None)."""
        if key is None:
            return compute()
        if key not in self._entries:
            with warnings.catch_warnings(record=True) as said:
                warnings.simplefilter("always")
                value = compute()
            self._entries[key] = (value, [(w.message, w.category) for w in said])
            while len(self._entries) > self.size:
                self._entries.popitem(last=False)
        self._entries.move_to_end(key)
        value, said = self._entries[key]
        for message, category in said:
            warnings.warn(message, category, stacklevel=3)
        return value

    def clear(self) -> None:
        """Forget every result."""
        self._entries.clear()

    def __len__(self) -> int:
        return len(self._entries)
