"""The files the commands write: output paths checked before any work, atomic writes, CSV text.

Three rules keep a user's files safe:

* an output may never be, nor contain, an input file (:func:`check_output`), even with ``--force``;
* an existing output file, or a non-empty output directory, is replaced only with ``--force``;
* every file is written whole or not at all (:func:`write_text`, :func:`write_with`): into a
  temporary file beside it, then renamed over it, so an interrupted run leaves no half-written file; it
  gets the mode a plain ``open`` would give (0644 under umask 022), for colleagues and servers to read.

Each check runs when a command starts, before it reads a record or derives an ARR, and names the
option at fault in a :class:`~bgphm.errors.UsageError` (exit code 2).

:func:`csv_text` is the counterpart of :func:`diagnosis.csv_reading.read_csv`: what ``bgphm simulate`` and
``bgphm demo`` write reads back as the same record.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from bgphm.errors import UsageError

__all__ = ["check_output", "csv_text", "file_digest", "input_files", "write_text", "write_with"]


def input_files(*candidates: str | os.PathLike | None) -> list[Path]:
    """The arguments that name existing files, resolved (a built-in model name such as ``dc-motor`` is not a file).

    >>> input_files(None, "dc-motor")
    []
    """
    return [Path(c).resolve() for c in candidates if c is not None and Path(c).is_file()]


def check_output(out: str | os.PathLike, *, kind: str, inputs: Iterable[Path] = (), force: bool = False,
                 option: str = "--out") -> Path:
    """Check an output path before any work; return it.

    Parameters
    ----------
    out : path
        The file (``kind="file"``) or directory (``kind="directory"``) to write.
    kind : {"file", "directory"}
    inputs : iterable of Path
        The input files of the command (:func:`input_files`); none may be ``out`` or lie inside it.
    force : bool
        Replace an existing file, or write into a non-empty directory (replacing the files of the
        same names, leaving the others).
    option : str
        The option named in the error.

    Raises
    ------
    UsageError
        ``out`` is or contains an input; exists and is of the other kind; exists (a file) or is
        not empty (a directory) without ``force``; or cannot be created or written.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> model = folder / "model.json"
    >>> _ = model.write_text("{}")
    >>> check_output(model, kind="file", inputs=[model.resolve()])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    bgphm.errors.UsageError: --out ...model.json is the input file ...: it would be overwritten; choose another name
    >>> check_output(folder, kind="directory", inputs=[model.resolve()])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    bgphm.errors.UsageError: --out ...: the directory holds the input file ...model.json, which could be ...
    >>> check_output(folder / "results", kind="directory") == folder / "results"
    True
    """
    if kind not in ("file", "directory"):
        raise ValueError(f"kind must be 'file' or 'directory', got {kind!r}")
    path = Path(out)
    target = path.resolve()
    for source in inputs:
        if source == target:
            raise UsageError(f"{option} {path} is the input file {source}: it would be overwritten; "
                             "choose another name")
        if kind == "directory" and target in source.parents:
            raise UsageError(f"{option} {path}: the directory holds the input file {source}, which could be "
                             "overwritten; choose another directory")
    if path.exists():
        _check_existing(path, kind, force, option)
    else:
        _check_creatable(path, option)
    return path


def _check_existing(path: Path, kind: str, force: bool, option: str) -> None:
    if kind == "file":
        if path.is_dir():
            raise UsageError(f"{option} {path} is a directory; give a file name")
        if not force:
            raise UsageError(f"{option} {path} exists; give --force to replace it")
        if not os.access(path.parent, os.W_OK):
            raise UsageError(f"{option} {path}: cannot write in {path.parent} (permission denied)")
        return
    if not path.is_dir():
        raise UsageError(f"{option} {path} exists and is not a directory")
    if any(path.iterdir()) and not force:
        raise UsageError(f"{option} {path} is not empty; give --force to write into it (files of the same names "
                         "are replaced, the others are kept)")
    if not os.access(path, os.W_OK | os.X_OK):
        raise UsageError(f"{option} {path}: cannot write in it (permission denied)")


def _check_creatable(path: Path, option: str) -> None:
    """The nearest existing ancestor must be a directory we may write in."""
    ancestor = path.absolute().parent
    while not ancestor.exists():
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise UsageError(f"{option} {path}: {ancestor} is a file, not a directory")
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise UsageError(f"{option} {path}: cannot create it in {ancestor} (permission denied)")


def write_with(path: str | os.PathLike, write: Callable[[Path], object]) -> Path:
    """Call ``write(temporary)`` for a temporary file beside ``path``, then rename it to ``path``.

    The rename is atomic: ``path`` holds either its old content or the whole new one, never a part,
    even if the run is interrupted.  The temporary file is removed if ``write`` fails.  Missing
    parent directories are created.

    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "a" / "x.txt"
    >>> write_with(target, lambda p: p.write_text("hello")).read_text()
    'hello'
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part" + path.suffix, dir=path.parent)
    os.close(handle)
    try:
        write(Path(temporary))
        os.chmod(temporary, 0o666 & ~_umask())  # mkstemp's file is private (0600); the output is as open() makes it
        os.replace(temporary, path)
    except BaseException:  # an interrupt included: leave no partial file behind
        Path(temporary).unlink(missing_ok=True)
        raise
    return path


def _umask() -> int:
    """The process' umask, read without changing it where Linux shows it (``/proc/self/status``): setting it to
    read it would race with threads creating files meanwhile."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except OSError:
        pass
    mask = os.umask(0o022)  # elsewhere: set and restore at once
    os.umask(mask)
    return mask


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically (see :func:`write_with`); return the path.

    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "x.json"
    >>> write_text(target, "{}").read_text()
    '{}'
    """
    return write_with(path, lambda p: p.write_text(text, encoding="utf-8"))


def file_digest(path: str | os.PathLike) -> str:
    """The SHA-256 of a file's bytes (hex), read in blocks: what a report or a manifest says of an input.

    >>> import tempfile, pathlib
    >>> target = write_text(pathlib.Path(tempfile.mkdtemp()) / "x.txt", "abc")
    >>> file_digest(target)[:16]
    'ba7816bf8f01cfea'
    """
    digest = hashlib.sha256()
    with open(path, "rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def csv_text(columns: Mapping[str, ArrayLike]) -> str:
    """CSV text of equally long columns: a header row of the names, one row per sample.

    Values are written with ``repr`` so that they read back exactly; NaN and infinities are
    written as empty cells, which :func:`~diagnosis.csv_reading.read_csv` reads as gaps.

    Parameters
    ----------
    columns : mapping of str to array_like
        Column name -> values, in the order of the columns.

    Returns
    -------
    str
        The CSV text, ending with a newline.

    Examples
    --------
    >>> print(csv_text({"t": [0.0, 0.1], "x": [1.5, float("nan")]}), end="")
    t,x
    0.0,1.5
    0.1,
    """
    names = list(columns)
    cells = [_cells(np.asarray(columns[n], float)) for n in names]
    if len({len(c) for c in cells}) > 1:
        raise ValueError("csv_text: columns of different lengths: "
                         + ", ".join(f"{n} ({len(c)})" for n, c in zip(names, cells)))
    lines = [",".join(names)] + [",".join(row) for row in zip(*cells)]
    return "\n".join(lines) + "\n"


def _cells(values: np.ndarray) -> list[str]:
    """One column's cells: ``repr`` of each finite value (a Python float's repr reads back exactly), else empty."""
    finite = np.isfinite(values)
    return [repr(v) if ok else "" for v, ok in zip(values.ravel().tolist(), finite.ravel().tolist())]
