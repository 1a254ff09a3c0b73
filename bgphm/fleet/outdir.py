"""The output directory of a fleet run: one writer at a time, shards staged, tables published whole.

Layout under ``--out``::

    .lock                        # held (flock) by the run writing here; released when its process ends
    .staging/plan.json           # during a run: what it runs (spec, records, shards, buckets)
    .staging/shards.jsonl        # one line per finished shard: its rows and its files' SHA-256
    .staging/rul/bucket=03/part-00012.parquet ...
    alarms/ estimates/ rul/ residuals/    # the published tables (Parquet, by asset bucket)
    summary.json
    index.html                   # the overview page (bgphm.fleet.page), built from the staged tables
    manifest.json                # written last: assets, shards, files and their SHA-256, settings

A run takes the lock first: a second run on the same ``--out`` is refused while the first lives.
Workers write each shard's files into ``.staging`` (hidden: pandas and pyarrow skip it), and the
driver records each finished shard.  At the end the tables are published: ``manifest.json`` goes,
each table's directory is swapped for its staged one in one rename (files a user put there move
along), ``summary.json`` and ``index.html`` are written, and ``manifest.json`` last.  A reader (:func:`~bgphm.fleet.
store.read_fleet`) requires the manifest and checks the files against it, so the tables it returns
are those of one whole run.  An interrupted run leaves the previous run's tables whole and its
finished shards staged; ``resume=True`` checks them against ``plan.json`` and the recorded
checksums and runs only the others: the tables equal those of an uninterrupted run, bit for bit.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
from collections.abc import Iterator
from pathlib import Path

from bgphm.errors import FleetError
from bgphm.files import file_digest, write_text
from prognosis.fleet.results import TABLES

__all__ = ["BUCKET", "MANIFEST", "PAGE", "PART", "STAGING", "Output", "locked", "read_manifest"]

LOCK = ".lock"
STAGING = ".staging"
PLAN = "plan.json"
DONE = "shards.jsonl"
MANIFEST = "manifest.json"
PAGE = "index.html"  # the overview page (bgphm.fleet.page), published with the tables
FORMAT = "bgphm fleet tables"
VERSION = 1
PART = re.compile(r"part-\d+\.parquet")  # a table's files: <table>/bucket=NN/part-SSSSS.parquet
BUCKET = re.compile(r"bucket=\d+")


@contextlib.contextmanager
def locked(out: Path) -> Iterator[None]:
    """Hold the exclusive lock of ``out`` (created if need be); refuse at once if another run holds it."""
    out.mkdir(parents=True, exist_ok=True)
    handle = os.open(out / LOCK, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        if not _try_lock(handle):
            raise FleetError(f"{out}: another fleet run is writing there (it holds {out / LOCK}); wait for it to "
                             "end, or choose another --out")
        yield
    finally:
        os.close(handle)  # closing releases the lock


def _try_lock(handle: int) -> bool:
    try:
        import fcntl
    except ImportError:  # Windows: a byte-range lock on the file
        import msvcrt
        try:
            msvcrt.locking(handle, msvcrt.LK_NBLCK, 1)
            return True
        except OSError:
            return False
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return True
    except BlockingIOError:
        return False


class Output:
    """The staging area and the publication of one run under ``out`` (the caller holds :func:`locked`)."""

    def __init__(self, out: str | os.PathLike):
        self.out = Path(out)
        self.staging = self.out / STAGING

    def start(self, plan: dict, *, resume: bool) -> dict[int, dict]:
        """Prepare the staging area for ``plan``; the shards already finished (resume) by number.

        Without ``resume`` a previous run's staging is discarded.  With it, the staged plan must be
        ``plan`` (same spec, records, shards and buckets), and a shard counts as finished only if
        every file it recorded is there with its recorded SHA-256 (the others run again).
        """
        if not resume:
            shutil.rmtree(self.staging, ignore_errors=True)
            self.staging.mkdir()
            write_text(self.staging / PLAN, json.dumps(plan, sort_keys=True))
            return {}
        try:
            staged = json.loads((self.staging / PLAN).read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise FleetError(f"{self.out}: nothing to resume (no interrupted fleet run there)") from None
        except (OSError, ValueError) as error:
            raise FleetError(f"{self.out}: cannot resume: {self.staging / PLAN} is unreadable ({error})") from None
        plan = json.loads(json.dumps(plan))  # as the staged one was read back: lists, not tuples
        if staged != plan:
            differs = sorted(k for k in set(staged) | set(plan) if staged.get(k) != plan.get(k))
            raise FleetError(f"{self.out}: cannot resume: the interrupted run had other {', '.join(differs)}; run "
                             "without --resume to start again")
        return {s["shard"]: s for s in self._recorded() if self._intact(s)}

    def finished(self, summary: dict) -> None:
        """Record a finished shard (its summary, with its files and their SHA-256)."""
        with open(self.staging / DONE, "a", encoding="utf-8") as stream:
            stream.write(json.dumps(summary, sort_keys=True) + "\n")
            stream.flush()
            os.fsync(stream.fileno())

    def publish(self, summary: dict, manifest: dict, page: str | None = None) -> None:
        """Swap each table for its staged one, then write ``summary.json``, the page and ``manifest.json`` (last).

        ``page`` is the text of ``index.html``; without it, an ``index.html`` there is removed (it would show
        another run's tables).
        """
        (self.out / MANIFEST).unlink(missing_ok=True)  # from here on, no reader takes the tables as whole
        for name in TABLES:
            staged, table = self.staging / name, self.out / name
            staged.mkdir(exist_ok=True)  # a table without rows is an empty directory
            old = self.staging / f"old-{name}"
            if table.is_dir():
                _move_foreign(table, staged)
                table.rename(old)
            staged.rename(table)
            shutil.rmtree(old, ignore_errors=True)
        write_text(self.out / "summary.json", json.dumps(summary, indent=2))
        if page is None:
            (self.out / PAGE).unlink(missing_ok=True)
        else:
            write_text(self.out / PAGE, page)
        write_text(self.out / MANIFEST, json.dumps({"format": FORMAT, "version": VERSION, **manifest}, indent=1))
        shutil.rmtree(self.staging, ignore_errors=True)

    def _recorded(self) -> list[dict]:
        try:
            lines = (self.staging / DONE).read_text(encoding="utf-8").splitlines()
        except FileNotFoundError:
            return []
        shards = []
        for line in lines:
            with contextlib.suppress(ValueError):  # a line cut by the interruption: that shard runs again
                shards.append(json.loads(line))
        return shards

    def _intact(self, summary: dict) -> bool:
        files = summary.get("files")
        if not isinstance(files, dict):
            return False
        for relative, digest in files.items():
            path = self.staging / relative
            if not path.is_file() or file_digest(path) != digest:
                return False
        return True


def _move_foreign(table: Path, staged: Path) -> None:
    """Move into ``staged`` the files of ``table`` that no run wrote (a user's notes): they stay published."""
    for path in sorted(table.rglob("*")):
        if path.is_file() and not PART.fullmatch(path.name):
            target = staged / path.relative_to(table)
            if not target.exists():
                target.parent.mkdir(parents=True, exist_ok=True)
                path.rename(target)


def read_manifest(out: Path) -> dict:
    """The manifest of a published run under ``out``, or a :class:`FleetError` saying why there is none."""
    path = out / MANIFEST
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        running = (out / STAGING).is_dir()
        raise FleetError(f"{out}: no {MANIFEST}: the fleet run " + (
            "is still running or was interrupted (bgphm fleet --resume goes on)" if running else
            "did not finish") + "; its tables are not whole") from None
    except (OSError, ValueError) as error:
        raise FleetError(f"{out}: {MANIFEST} is unreadable ({error})") from None
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT or manifest.get("version") != VERSION:
        raise FleetError(f"{out}: {MANIFEST} is not the manifest of a fleet run this toolkit reads")
    return manifest
