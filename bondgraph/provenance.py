"""Where a generated document comes from: the tool's version, when it was made, and which model.

A report that leaves the toolkit (an ARR report in an engineering document, a run report) says
what made it, so that a reader can tell two versions apart and redo it:

* the version of the installed distribution ``bondgraph-phm`` (and of sympy, which writes the
  equations);
* the time it was made, in UTC, to the second; ``SOURCE_DATE_EPOCH`` (seconds since 1970-01-01
  UTC, the reproducible-builds convention) stands in for the clock when it is set, so that the
  same inputs give the same bytes;
* the model's SHA-256 (:func:`model_sha256`): of its canonical JSON, so that the same model gives
  the same hash whatever order its elements and bonds were added in.

Example
-------
>>> import os
>>> from bondgraph.library import rlc_circuit
>>> os.environ["SOURCE_DATE_EPOCH"] = "1700000000"
>>> record = provenance(rlc_circuit())
>>> del os.environ["SOURCE_DATE_EPOCH"]
>>> record.generated, record.tool, len(record.model_sha256)
('2023-11-14 22:13:20 UTC', 'bondgraph-phm', 64)
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from datetime import datetime, timezone
from importlib import metadata

from .errors import SettingError
from .io import to_json
from .model import BondGraph

__all__ = ["DISTRIBUTION", "MODEL_HASH_SOURCE", "Provenance", "generated_at", "model_sha256", "provenance",
           "tool_version"]

#: The distribution name of the toolkit (``[project] name`` in pyproject.toml).
DISTRIBUTION = "bondgraph-phm"

#: What :func:`model_sha256` hashes, in words, for a report to print beside the hash.
MODEL_HASH_SOURCE = ("SHA-256 of the model's canonical JSON: bondgraph.io.to_json of its name, its elements with "
                     "every attribute a model file holds and its bonds; nodes sorted by id, bonds by their ends, "
                     "keys sorted, no whitespace")


@dataclass(frozen=True)
class Provenance:
    """What made a document and from what.

    Attributes
    ----------
    tool : str
        The distribution, ``bondgraph-phm``.
    version : str
        Its installed version, or ``"unknown"`` when it runs from a source tree that is not installed.
    sympy : str
        The version of sympy, which writes the equations.
    generated : str
        When, ``YYYY-MM-DD HH:MM:SS UTC`` (:func:`generated_at`).
    model_sha256 : str
        64 hexadecimal digits (:func:`model_sha256`).
    hashed : str
        What the hash is of, in words.
    """

    tool: str
    version: str
    sympy: str
    generated: str
    model_sha256: str
    hashed: str = MODEL_HASH_SOURCE


def provenance(bg: BondGraph) -> Provenance:
    """The provenance of a document made now (or at ``SOURCE_DATE_EPOCH``) from ``bg``.

    Examples
    --------
    >>> from bondgraph.library import dc_motor
    >>> record = provenance(dc_motor())
    >>> record.model_sha256 == model_sha256(dc_motor()), record.generated.endswith(" UTC")
    (True, True)
    """
    return Provenance(DISTRIBUTION, tool_version(), _version("sympy"), generated_at(), model_sha256(bg))


def tool_version() -> str:
    """The installed version of ``bondgraph-phm``, or ``"unknown"`` when it is not installed.

    >>> tool_version() != ""
    True
    """
    return _version(DISTRIBUTION)


def _version(distribution: str) -> str:
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:  # run from a source tree without `pip install`: say so, do not fail
        return "unknown"


#: How an error names the variable: spelt out, not through ``{setting}``, which a command line would turn
#: into an option name (``--source-date-epoch``) that does not exist.
_ENVIRONMENT = "environment variable SOURCE_DATE_EPOCH"


def generated_at(environ: dict | None = None) -> str:
    """The time a document is made, ``YYYY-MM-DD HH:MM:SS UTC``: ``SOURCE_DATE_EPOCH`` when set, else now.

    Parameters
    ----------
    environ : mapping, optional
        Where to read ``SOURCE_DATE_EPOCH``; default :data:`os.environ`.

    Raises
    ------
    SettingError
        ``SOURCE_DATE_EPOCH`` is set but is not a whole non-negative number of seconds.

    Examples
    --------
    >>> generated_at({"SOURCE_DATE_EPOCH": "0"})
    '1970-01-01 00:00:00 UTC'
    >>> generated_at({"SOURCE_DATE_EPOCH": "yesterday"})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    bondgraph.errors.SettingError: environment variable SOURCE_DATE_EPOCH: 'yesterday' is not a whole number ...
    """
    value = (os.environ if environ is None else environ).get("SOURCE_DATE_EPOCH")
    if value is None or value == "":
        moment = datetime.now(timezone.utc)
    else:
        if not value.isascii() or not value.isdigit():
            # a build that asks to be reproducible and is not should stop, not quietly use the clock
            raise SettingError("SOURCE_DATE_EPOCH", f"{_ENVIRONMENT}: {value[:40]!r} is not a whole number of "
                               "seconds since 1970-01-01 UTC")
        try:
            moment = datetime.fromtimestamp(int(value), timezone.utc)
        except (OverflowError, OSError, ValueError):
            raise SettingError("SOURCE_DATE_EPOCH", f"{_ENVIRONMENT}: {value[:40]!r} is out of the range of dates") \
                from None
    return moment.strftime("%Y-%m-%d %H:%M:%S UTC")


def model_sha256(bg: BondGraph) -> str:
    """The SHA-256 (hex) of a model's canonical JSON: the same model gives the same hash.

    The JSON is :func:`bondgraph.io.to_json` of the bond graph (its name, every element with the
    attributes a model file holds: kind, parameter, value, uncertainty, law, modulus, signal, ...; and
    the bonds), with the nodes sorted by id, the bonds by their ends and the keys sorted, written
    without whitespace.  Simulation settings (inputs, end time) are not part of the model and are not
    hashed.  Laws are hashed as sympy prints them, so another sympy version may print (and hash) the
    same law differently.

    Examples
    --------
    >>> from bondgraph import BondGraph
    >>> from bondgraph.library import rlc_circuit
    >>> def circuit(order):
    ...     bg = BondGraph(name="RC")
    ...     for name, kind, value in order:
    ...         bg.add(name, kind, value=value)
    ...     bg.bond("V", "J"); bg.bond("J", "R")
    ...     return bg
    >>> nodes = [("V", "Se", None), ("J", "1", None), ("R", "R", 2.0)]
    >>> model_sha256(circuit(nodes)) == model_sha256(circuit(nodes[::-1]))
    True
    >>> model_sha256(rlc_circuit()) == model_sha256(rlc_circuit(R=11.0))
    False
    """
    data = json.loads(to_json(bg, indent=None))
    data["nodes"].sort(key=lambda node: _key(node["id"]))
    data["links"].sort(key=lambda link: (_key(link["source"]), _key(link["target"])))
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def _key(node_id) -> tuple:
    """A sort key for node ids that may be strings or integers (which do not compare with each other)."""
    return (isinstance(node_id, str), str(node_id))
