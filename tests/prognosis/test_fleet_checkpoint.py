"""Fleet checkpoints as data: a file that runs no code, refuses any alteration, and a content checked key by key."""

import copy
import hashlib
import io
import pathlib
import pickle

import numpy as np
import pytest

from prognosis.errors import PrognosisError
from prognosis.fleet import FleetResult
from prognosis.fleet.checkpoint import read_checkpoint, write_checkpoint
from tests.prognosis.test_fleet import circuit, fleet, same, stream  # noqa: F401 (circuit: a fixture)

STOP = 600  # samples streamed before the checkpoint: c1 and c4 are filtering, c3 alarms 23 samples later


@pytest.fixture(scope="module")
def stopped(circuit):  # noqa: F811
    """A monitor streamed up to STOP, its results so far and its checkpoint."""
    arr, records = circuit
    monitor = fleet(arr)
    before = stream(monitor, records, sizes=[50], stop=STOP)
    return monitor, before, monitor.checkpoint()


def test_a_checkpoint_file_goes_on_as_if_never_stopped(circuit, stopped, tmp_path):  # noqa: F811
    arr, records = circuit
    monitor, before, _ = stopped
    path = tmp_path / "fleet.ckpt.npz"
    monitor.checkpoint(path)
    resumed = fleet(arr)
    resumed.restore(path)
    after = stream(resumed, records, sizes=[50], start=STOP)
    uninterrupted = stream(fleet(arr), records, sizes=[50])
    for asset in ("c1", "c3", "c4"):
        assert same(uninterrupted, FleetResult.concat([before, after]), asset)
    assert not list(tmp_path.glob("*.partial"))   # written beside, then renamed: no leftover


def test_a_pickle_or_a_pickled_array_is_refused_without_running_it(stopped, tmp_path, circuit):  # noqa: F811
    arr, _ = circuit
    marker = tmp_path / "ran"

    class Payload:
        def __reduce__(self):
            return pathlib.Path.touch, (marker,)

    crafted = tmp_path / "crafted.npz"
    crafted.write_bytes(pickle.dumps({"version": 1, "assets": Payload()}))
    with pytest.raises(PrognosisError, match="crafted.npz.*checksum does not match"):
        fleet(arr).restore(crafted)
    # a pickled array inside a valid archive, sealed as the writer seals (the seal is no secret)
    buffer = io.BytesIO()
    np.savez(buffer, header=np.frombuffer(b"{}", np.uint8), a0=np.array([Payload()], dtype=object))
    body = buffer.getvalue()
    inside = tmp_path / "inside.npz"
    inside.write_bytes(body + b"sha256:" + hashlib.sha256(body).hexdigest().encode())
    with pytest.raises(PrognosisError, match="inside.npz.*not a readable checkpoint.*allow_pickle"):
        read_checkpoint(inside)
    assert not marker.exists()


def test_a_truncated_or_altered_file_is_refused_naming_it(stopped, tmp_path, circuit):  # noqa: F811
    arr, _ = circuit
    monitor, _, _ = stopped
    path = tmp_path / "fleet.ckpt.npz"
    monitor.checkpoint(path)
    whole = path.read_bytes()
    cut = tmp_path / "cut.npz"
    cut.write_bytes(whole[: len(whole) // 2])
    with pytest.raises(PrognosisError, match="cut.npz"):
        fleet(arr).restore(cut)
    # an array rewritten consistently (a valid archive, a valid npy) but not by the writer: no seal
    with np.load(path, allow_pickle=False) as archive:
        entries = {key: archive[key] for key in archive.files}
    theta = max((k for k in entries if k != "header"), key=lambda k: entries[k].size)
    entries[theta] = entries[theta] * 1.0000001
    forged = tmp_path / "forged.npz"
    np.savez(forged, **entries)
    with pytest.raises(PrognosisError, match="forged.npz.*checksum does not match"):
        fleet(arr).restore(forged)


def test_every_bit_flip_is_refused(stopped, tmp_path):
    """The seal covers every byte: a flip in the numbers, the header, the archive's structure or the seal."""
    monitor, _, _ = stopped
    path = tmp_path / "fleet.ckpt.npz"
    monitor.checkpoint(path)
    whole = path.read_bytes()
    rng = np.random.default_rng(32)
    flipped = tmp_path / "flipped.npz"
    for position, bit in zip(rng.integers(0, len(whole), 200), rng.integers(0, 8, 200)):
        damaged = bytearray(whole)
        damaged[position] ^= 1 << int(bit)
        flipped.write_bytes(bytes(damaged))
        with pytest.raises(PrognosisError, match="flipped.npz.*checksum does not match"):
            read_checkpoint(flipped)
    for position in (0, len(whole) // 3, len(whole) - 1):   # the first, a middle and the last byte too
        damaged = bytearray(whole)
        damaged[position] ^= 0x80
        flipped.write_bytes(bytes(damaged))
        with pytest.raises(PrognosisError, match="checksum does not match"):
            read_checkpoint(flipped)


BAD = {
    "NaN particles": (lambda s: _rows(s)["theta"].__setitem__((0, 0), np.nan), r"rows\.theta holds values"),
    "particles x1e6": (lambda s: _rows(s).__setitem__("theta", _rows(s)["theta"] * 1e6), r"rows\.theta: particles"),
    "a broadcast theta": (lambda s: _rows(s).__setitem__("theta", _rows(s)["theta"][0]), r"rows\.theta has shape"),
    "stride 0": (lambda s: _alarmed(s).__setitem__("stride", 0), r"\.stride must be a whole number >= 1"),
    "stride -3": (lambda s: _alarmed(s).__setitem__("stride", -3), r"\.stride must be a whole number >= 1"),
    "a duplicated asset": (lambda s: s["assets"].append(copy.deepcopy(s["assets"][0])), r"repeats assets\[0\]"),
    "7 and '7'": (lambda s: (s["assets"][0].__setitem__("asset", 7),
                            s["assets"][1].__setitem__("asset", "7")), r"asset '7' repeats assets\[0\]"),
    "an unknown key": (lambda s: s["assets"][0].__setitem__("extra", 1), r"unknown keys \['extra'\]"),
    "a missing key": (lambda s: s["assets"][0].pop("count"), r"lacks \['count'\]"),
    "an alarm after the samples": (lambda s: _alarmed(s).__setitem__("alarm", 10**9), r"\.alarm: sample"),
    "a float step": (lambda s: _rows(s).__setitem__("steps", _rows(s)["steps"] + 0.5),
                     r"rows\.steps: expected an array of whole numbers"),
    "an evaluator's NaN time": (lambda s: s["assets"][0]["evaluators"][0]["t"].__setitem__(0, np.nan),
                                r"evaluators\[0\]\.t holds values"),
}


@pytest.mark.parametrize("attack", sorted(BAD))
def test_a_checkpoint_that_cannot_be_right_is_refused_naming_the_key(stopped, circuit, tmp_path, attack):  # noqa: F811
    arr, _ = circuit
    _, _, saved = stopped
    state = copy.deepcopy(saved)
    change, message = BAD[attack]
    change(state)
    monitor = fleet(arr)
    untouched = monitor.checkpoint()
    with pytest.raises(PrognosisError, match=message):
        monitor.restore(state)
    assert _equal(monitor.checkpoint(), untouched)   # a refused checkpoint changes nothing
    if attack not in ("7 and '7'",):   # the file holds the same content: refused the same way
        path = tmp_path / "attack.npz"
        write_checkpoint(state, path)
        with pytest.raises(PrognosisError, match=message):
            fleet(arr).restore(path)


def test_what_is_not_plain_data_is_not_written(tmp_path):
    with pytest.raises(PrognosisError, match=r"checkpoint\.assets\[0\]: a object is not plain data"):
        write_checkpoint({"assets": [object()]}, tmp_path / "x.npz")
    with pytest.raises(PrognosisError, match="array of <U1 is not plain data"):
        write_checkpoint({"names": np.array(["a"])}, tmp_path / "x.npz")
    assert not list(tmp_path.iterdir())


def _rows(state: dict) -> dict:
    return next(a["rows"] for a in state["assets"] if "rows" in a)


def _alarmed(state: dict) -> dict:
    return next(a for a in state["assets"] if a["stride"] is not None)


def _equal(first, second) -> bool:
    """Two states equal to the last bit (tuples and lists alike, NaN equal to NaN)."""
    if isinstance(first, dict) and isinstance(second, dict):
        return first.keys() == second.keys() and all(_equal(first[k], second[k]) for k in first)
    if isinstance(first, (list, tuple)) and isinstance(second, (list, tuple)):
        return len(first) == len(second) and all(_equal(a, b) for a, b in zip(first, second))
    if isinstance(first, np.ndarray) or isinstance(second, np.ndarray):
        a, b = np.asarray(first), np.asarray(second)
        return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    if isinstance(first, float) and isinstance(second, float):
        return first == second or (first != first and second != second)
    return first == second and type(first) is type(second)
