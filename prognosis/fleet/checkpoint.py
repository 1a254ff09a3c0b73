"""Fleet checkpoints as data: numeric arrays in an ``.npz`` archive under a JSON header, never a pickle.

:meth:`FleetMonitor.checkpoint <prognosis.fleet.FleetMonitor.checkpoint>` returns the streaming state
as nested dicts and lists of numbers, strings and numeric arrays; :func:`write_checkpoint` stores it
and :func:`read_checkpoint` reads it back, equal to the last bit.  The archive (a zip of ``.npy``
files, as ``numpy.savez`` writes) holds one entry per array (``a0``, ``a1``, ...) and a ``header``:
the format's name and version and the layout (the nested structure, each array replaced by
``{"$array": name}`` and each non-finite float by ``{"$float": "nan"}``).  Its comment, the file's
last bytes, seals it: the SHA-256 of every byte before.  Reading checks the seal before numpy sees
the file, then opens it with ``allow_pickle=False`` and checks the header and the entries: a file
cannot run code, and an altered or damaged one (any flipped bit, a truncation) is refused with one
line naming the file.

:func:`check_state` then checks the content against the monitor that takes it up (every key, shape,
dtype, finiteness and range), so that a checkpoint built in memory is held to the same rules.

Examples
--------
>>> import tempfile, pathlib
>>> state = {"version": 1, "assets": [{"asset": "pump-7", "count": 3, "t": np.arange(3.0), "step": float("nan")}]}
>>> with tempfile.TemporaryDirectory() as folder:
...     path = pathlib.Path(folder) / "fleet.ckpt.npz"
...     write_checkpoint(state, path)
...     again = read_checkpoint(path)
>>> again["assets"][0]["asset"], again["assets"][0]["t"].tolist(), again["assets"][0]["step"]
('pump-7', [0.0, 1.0, 2.0], nan)
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import tempfile
import zipfile
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from ..errors import PrognosisError

__all__ = ["read_checkpoint", "write_checkpoint", "check_state"]

FORMAT = "bgphm fleet checkpoint"
VERSION = 1
HEADER = "header"
NUMERIC = "biuf"  # dtype kinds an array of a checkpoint may have: bool, integers, floats
#: particles farther from the nominal value than this many times the way to failure are refused: no
#: filter puts them there (the hypothesis is rejected long before), a scaled or corrupted state does
PLAUSIBLE = 1e3


# -- the file ----------------------------------------------------------------------------------------
def write_checkpoint(state: Mapping, path: str | os.PathLike) -> None:
    """Write ``state`` (nested dicts with text keys, lists, numbers, text, None, numeric arrays) to ``path``.

    The file appears whole or not at all (written beside it, then renamed).  Raises a
    :class:`~prognosis.errors.PrognosisError` naming the key of a value that is not plain data.
    """
    arrays: dict[str, np.ndarray] = {}
    layout = _encode(state, arrays, "checkpoint")
    header = json.dumps({"format": FORMAT, "version": VERSION, "layout": layout}, sort_keys=True).encode()
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_STORED) as archive:
        for key, array in {HEADER: np.frombuffer(header, dtype=np.uint8), **arrays}.items():
            with archive.open(f"{key}.npy", "w", force_zip64=True) as member:
                np.lib.format.write_array(member, array, allow_pickle=False)
        archive.comment = b"\0" * len(_seal(b""))  # the seal's place, filled below
    body = buffer.getvalue()[:-len(_seal(b""))]
    path = Path(path)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".partial")
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(body + _seal(body))
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def read_checkpoint(path: str | os.PathLike) -> dict:
    """The state a :func:`write_checkpoint` file holds, after checking its seal, format and version."""
    name = os.fsdecode(path)
    try:
        content = Path(path).read_bytes()
    except FileNotFoundError:
        raise PrognosisError(f"checkpoint {name!r}: no such file") from None
    except OSError as error:
        raise PrognosisError(f"checkpoint {name!r}: cannot be read ({error.strerror or error})") from None
    size = len(_seal(b""))
    if len(content) <= size or content[-size:] != _seal(content[:-size]):
        raise PrognosisError(f"checkpoint {name!r}: its checksum does not match: the file was altered, damaged or "
                             "not written by write_checkpoint")
    try:
        with np.load(io.BytesIO(content), allow_pickle=False) as archive:
            entries = {key: archive[key] for key in archive.files}
    except Exception as error:  # sealed yet unreadable: written by another tool; numpy fails its own way
        raise PrognosisError(f"checkpoint {name!r}: not a readable checkpoint file "
                             f"({type(error).__name__}: {error})") from None
    layout = _header(entries.pop(HEADER, None), name)["layout"]
    named = set(_array_names(layout))
    if named != set(entries):
        raise PrognosisError(f"checkpoint {name!r}: its arrays {sorted(entries)} are not those its header lists "
                             f"{sorted(named)}")
    return _decode(layout, entries)


def _seal(body: bytes) -> bytes:
    """The last bytes of a checkpoint (the archive's comment): the SHA-256 of every byte before them."""
    return b"sha256:" + hashlib.sha256(body).hexdigest().encode()


def _header(raw: np.ndarray | None, name: str) -> dict:
    if raw is None or raw.dtype != np.uint8 or raw.ndim != 1:
        raise PrognosisError(f"checkpoint {name!r}: no header: not a checkpoint file")
    try:
        header = json.loads(raw.tobytes().decode())
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise PrognosisError(f"checkpoint {name!r}: its header is not JSON") from None
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise PrognosisError(f"checkpoint {name!r}: not a checkpoint file")
    if header.get("version") != VERSION:
        raise PrognosisError(f"checkpoint {name!r}: unknown version {header.get('version')!r} (this toolkit reads "
                             f"version {VERSION})")
    if "layout" not in header:
        raise PrognosisError(f"checkpoint {name!r}: its header lacks the layout")
    return header


def _encode(value, arrays: dict, where: str):
    """``value`` as JSON, its arrays moved to ``arrays``; ``where`` names it in an error."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, bool) or value is None:
        return value
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else {"$float": repr(value)}
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in NUMERIC:
            raise PrognosisError(f"{where}: an array of {value.dtype} is not plain data (numbers or booleans only)")
        key = f"a{len(arrays)}"
        arrays[key] = np.ascontiguousarray(value)
        return {"$array": key}
    if isinstance(value, Mapping):
        if not all(isinstance(k, str) and not k.startswith("$") for k in value):
            raise PrognosisError(f"{where}: keys must be text not starting with '$', got {list(value)!r}")
        return {k: _encode(v, arrays, f"{where}.{k}") for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_encode(v, arrays, f"{where}[{i}]") for i, v in enumerate(value)]
    raise PrognosisError(f"{where}: a {type(value).__name__} is not plain data")


def _decode(layout, arrays: Mapping[str, np.ndarray]):
    if isinstance(layout, dict):
        if set(layout) == {"$array"}:
            return arrays[layout["$array"]]
        if set(layout) == {"$float"}:
            return float(layout["$float"])
        return {k: _decode(v, arrays) for k, v in layout.items()}
    if isinstance(layout, list):
        return [_decode(v, arrays) for v in layout]
    return layout


def _array_names(layout):
    if isinstance(layout, dict):
        if set(layout) == {"$array"}:
            yield layout["$array"]
        else:
            for value in layout.values():
                yield from _array_names(value)
    elif isinstance(layout, list):
        for value in layout:
            yield from _array_names(value)


# -- the content ---------------------------------------------------------------------------------------
ASSET_KEYS = {"asset", "evaluators", "persistence", "pending", "count", "recent", "alarm", "stride", "sample_step",
              "hypotheses", "starts"}
OPTIONAL_KEYS = {"queue", "rows"}


def check_state(checkpoint: Mapping, *, arrs: int, hypotheses: Sequence, particles: int, gammas: int,
                domains: np.ndarray, row_state: Sequence[str]) -> None:
    """Refuse a checkpoint whose content this monitor cannot go on from, naming the key at fault.

    ``arrs``: the monitor's ARR count; ``hypotheses``: its hypotheses (``nominal``, ``failure``);
    ``particles``, ``gammas``: particles per row and gammas per particle; ``domains`` (H, 2): each
    hypothesis' physical domain; ``row_state``: the filter's per-row arrays.
    """
    if not isinstance(checkpoint, Mapping):
        raise PrognosisError(f"checkpoint: expected the dict FleetMonitor.checkpoint() returns or a checkpoint file, "
                             f"got {type(checkpoint).__name__}")
    extra = set(checkpoint) - {"version", "settings", "assets"}
    if extra:
        raise PrognosisError(f"checkpoint: unknown keys {sorted(extra)}")
    assets = checkpoint.get("assets")
    if not isinstance(assets, list):
        raise PrognosisError("checkpoint: assets must be a list of asset states")
    seen: dict[str, int] = {}
    for i, state in enumerate(assets):
        where = f"checkpoint: assets[{i}]"
        if not isinstance(state, Mapping):
            raise PrognosisError(f"{where} must be a dict")
        missing, unknown = ASSET_KEYS - set(state), set(state) - ASSET_KEYS - OPTIONAL_KEYS
        if missing or unknown:
            raise PrognosisError(f"{where}: " + "; ".join(
                part for part in (missing and f"lacks {sorted(missing)}", unknown and f"unknown keys {sorted(unknown)}")
                if part))
        asset = state["asset"]
        if not (isinstance(asset, str) or _is_whole(asset)):
            raise PrognosisError(f"{where}.asset must be text or a whole number, got {asset!r}")
        if str(asset) in seen:
            raise PrognosisError(f"{where}.asset {asset!r} repeats assets[{seen[str(asset)]}] (ids are compared as "
                                 "text)")
        seen[str(asset)] = i
        where = f"checkpoint: asset {asset!r}"
        _check_asset(state, where, arrs, len(hypotheses))
        if "rows" in state:
            _check_rows(state, where, hypotheses, particles, gammas, domains, row_state)


def _check_asset(state: Mapping, where: str, arrs: int, count: int) -> None:
    _whole(state["persistence"], f"{where}.persistence", 1)
    samples = _whole(state["count"], f"{where}.count", 0)
    if state["alarm"] is not None and _whole(state["alarm"], f"{where}.alarm", 0) > samples:
        raise PrognosisError(f"{where}.alarm: sample {state['alarm']} is beyond the {samples} samples seen")
    if state["stride"] is not None:
        _whole(state["stride"], f"{where}.stride", 1)
    if state["sample_step"] is not None:
        _positive(state["sample_step"], f"{where}.sample_step")
    for key in ("evaluators", "pending"):
        if not isinstance(state[key], (list, tuple)) or len(state[key]) != arrs:
            raise PrognosisError(f"{where}.{key}: expected one entry per ARR ({arrs})")
    for m, evaluator in enumerate(state["evaluators"]):
        _check_evaluator(evaluator, f"{where}.evaluators[{m}]")
    for m, part in enumerate(state["pending"]):
        _check_final(part, f"{where}.pending[{m}]", 1)
    _check_final(state["recent"], f"{where}.recent", arrs)
    started = state["hypotheses"]
    if not isinstance(started, (list, tuple)) or len({int(h) for h in started if _is_whole(h)}) != len(started) \
            or not all(_is_whole(h) and 0 <= h < count for h in started):
        raise PrognosisError(f"{where}.hypotheses: expected distinct hypothesis numbers below {count}, got {started!r}")
    starts = state["starts"]
    if not isinstance(starts, (list, tuple)) or len(starts) != len(started):
        raise PrognosisError(f"{where}.starts: expected one (lo, hi, sigma_v) per started hypothesis")
    for s in starts:
        values = np.asarray(s, dtype=float) if _numbers(s) else None
        if values is None or values.shape != (3,) or not np.all(np.isfinite(values)) or values[0] > values[1] \
                or values[2] < 0:
            raise PrognosisError(f"{where}.starts: {s!r} is not (lo <= hi, sigma_v >= 0), all finite")
    for k, item in enumerate(state.get("queue", [])):
        if not (isinstance(item, (list, tuple)) and len(item) == 3 and isinstance(item[2], (list, tuple))
                and len(item[2]) == arrs):
            raise PrognosisError(f"{where}.queue[{k}]: expected (t, y, points per ARR)")
        _finite(item[0], f"{where}.queue[{k}].t")
        _array(item[1], f"{where}.queue[{k}].y", "f", (arrs,))
        for m, points in enumerate(item[2]):
            _array(points, f"{where}.queue[{k}].points[{m}]", "f", None, ndim=1)


def _check_evaluator(state, where: str) -> None:
    """What the online evaluation of one ARR holds; its fit to the ARR is checked when it is restored."""
    if not isinstance(state, Mapping):
        raise PrognosisError(f"{where} must be a dict")
    for key in ("samples", "final", "run"):
        _whole(state.get(key), f"{where}.{key}", 0)
    _array(state.get("t"), f"{where}.t", "f", None, ndim=1)
    for key in ("buffer", "origin", "integrals", "integrands"):
        array = _array(state.get(key), f"{where}.{key}", "f", None, finite=False)
        if np.any(np.isinf(array)):
            raise PrognosisError(f"{where}.{key} holds infinite values")
    _array(state.get("unknown"), f"{where}.unknown", "b", None)


def _check_final(part, where: str, columns: int) -> None:
    """Aligned final samples (``live.Final`` as plain data): t (n,), y and alarm (n, columns), points."""
    if part is None:
        return
    if not isinstance(part, Mapping) or set(part) != {"t", "y", "alarm", "points"}:
        raise PrognosisError(f"{where}: expected t, y, alarm and points")
    t = _array(part["t"], f"{where}.t", "f", None, ndim=1)
    n = t.shape[0]
    _array(part["y"], f"{where}.y", "f", (n, columns), finite=False)
    _array(part["alarm"], f"{where}.alarm", "b", (n, columns))
    if not isinstance(part["points"], list) or len(part["points"]) != columns:
        raise PrognosisError(f"{where}.points: expected one array per ARR ({columns})")
    for m, points in enumerate(part["points"]):
        array = _array(points, f"{where}.points[{m}]", "f", None, ndim=2, finite=False)
        if array.shape[0] != n:
            raise PrognosisError(f"{where}.points[{m}] has {array.shape[0]} rows, expected {n}")


def _check_rows(state: Mapping, where: str, hypotheses: Sequence, particles: int, gammas: int,
                domains: np.ndarray, row_state: Sequence[str]) -> None:
    rows = state["rows"]
    if not isinstance(rows, Mapping) or set(rows) != set(row_state):
        raise PrognosisError(f"{where}.rows: expected the arrays {sorted(row_state)}")
    count = len(state["hypotheses"])
    shapes = {"theta": ("f", (count, particles)), "gamma": ("f", (count, gammas, particles)),
              "hypothesis": ("i", (count,)), "mean": ("f", (count, gammas)), "variance": ("f", (count, gammas)),
              "sigma_v": ("f", (count,)), "log_evidence": ("f", (count,)), "steps": ("i", (count,)),
              "rejected": ("b", (count,)), "away": ("i", (count,))}
    arrays = {key: _array(rows[key], f"{where}.rows.{key}", *shapes[key], finite=key != "log_evidence")
              for key in row_state}
    if arrays["hypothesis"].tolist() != list(state["hypotheses"]):
        raise PrognosisError(f"{where}.rows.hypothesis {arrays['hypothesis'].tolist()} is not the asset's hypotheses "
                             f"{state['hypotheses']}")
    evidence = arrays["log_evidence"]
    if np.any(np.isnan(evidence) | (evidence == np.inf)):
        raise PrognosisError(f"{where}.rows.log_evidence must be finite or -inf")
    for key in ("variance", "sigma_v", "steps", "away"):
        if np.any(arrays[key] < 0):
            raise PrognosisError(f"{where}.rows.{key} must be >= 0")
    theta = arrays["theta"]
    for r, h in enumerate(arrays["hypothesis"]):
        lo, hi = domains[h]
        nominal, failure = hypotheses[h].nominal, hypotheses[h].failure
        reach = PLAUSIBLE * abs(failure - nominal)
        if np.any(theta[r] <= lo) or np.any(theta[r] >= hi) or np.any(np.abs(theta[r] - nominal) > reach):
            raise PrognosisError(f"{where}.rows.theta: particles of {hypotheses[h].name} lie outside their domain "
                                 f"({lo:g}, {hi:g}) or beyond {PLAUSIBLE:g} times the way to failure from "
                                 f"{nominal:g}")


def _array(value, where: str, kind: str, shape, *, ndim: int | None = None, finite: bool = True) -> np.ndarray:
    """``value`` checked to be an array of ``kind`` ("f" numbers, "i" whole numbers, "b" booleans)."""
    if not isinstance(value, np.ndarray) or value.dtype.kind not in _KINDS[kind]:
        got = value.dtype if isinstance(value, np.ndarray) else type(value).__name__
        raise PrognosisError(f"{where}: expected an array of {_KIND_NAMES[kind]}, got {got}")
    if shape is not None and value.shape != tuple(shape):
        raise PrognosisError(f"{where} has shape {value.shape}, expected {tuple(shape)}")
    if ndim is not None and value.ndim != ndim:
        raise PrognosisError(f"{where} has {value.ndim} dimensions, expected {ndim}")
    if finite and kind == "f" and not np.all(np.isfinite(value)):
        raise PrognosisError(f"{where} holds values that are not finite")
    return value


_KINDS = {"f": "fiu", "i": "iu", "b": "b"}
_KIND_NAMES = {"f": "numbers", "i": "whole numbers", "b": "booleans"}


def _is_whole(value) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def _whole(value, where: str, least: int) -> int:
    if not _is_whole(value) or value < least:
        raise PrognosisError(f"{where} must be a whole number >= {least}, got {value!r}")
    return int(value)


def _positive(value, where: str) -> float:
    if not _is_number(value) or not math.isfinite(value) or value <= 0:
        raise PrognosisError(f"{where} must be a finite number > 0, got {value!r}")
    return float(value)


def _finite(value, where: str) -> float:
    if not _is_number(value) or not math.isfinite(value):
        raise PrognosisError(f"{where} must be a finite number, got {value!r}")
    return float(value)


def _is_number(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def _numbers(values) -> bool:
    return isinstance(values, (list, tuple)) and all(_is_number(v) for v in values)
