"""Running a fleet job: asset ids in shards, shards on Dask workers (or in this process), tables to Parquet.

The driver lists the asset ids, sorts them and cuts them into shards of a fixed size; each shard is
one task, :func:`run_shard`, whose arguments are the :class:`~bgphm.fleet.spec.FleetSpec`, the
record source (a path), the shard's ids and the output directory: a few kilobytes.  A worker builds
the ARRs and the :class:`~prognosis.fleet.FleetMonitor` once (:func:`~bgphm.fleet.spec.monitor_for`),
reads its shard's records one at a time, runs them through the monitor and writes the tables to
Parquet (:mod:`bgphm.fleet.store`); only a small summary comes back to the driver.

Randomness is keyed by (seed, asset, step) (:mod:`prognosis.random_streams`), so an asset's rows are the
same in any shard, on any worker, and in the serial run.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import signal
import socket
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import NamedTuple

from bgphm.errors import FleetError, FleetWarning, MissingExtraError, UsageError

from bgphm.run_report import provenance
from bgphm.units import units_of
from prognosis.fleet.results import TABLES

from .outdir import Output, locked
from .page import fleet_page
from .sources import open_source
from .spec import FleetSpec, monitor_for
from .store import BUCKETS, read_tables, write_shard

__all__ = ["SERIAL", "WORKERS", "Task", "default_shard_size", "local_cluster", "malloc_setting", "plan", "require_dask",
           "run_fleet", "run_shard", "shard_assets"]

SERIAL = "serial"  # the scheduler name of the in-process run (no Dask)
WORKERS = 2  # worker processes of a local cluster by default (this machine's cores)
MAX_SHARD = 1000  # assets per shard by default at most: FleetMonitor filters up to 1000 assets together
CONNECT_TIMEOUT = "10s"  # to reach a remote scheduler
WORKER_TIMEOUT = 60.0  # seconds to wait for a first worker on a remote scheduler
MALLOC = "MALLOC_TRIM_THRESHOLD_"


class Task(NamedTuple):
    """One shard's work: what travels to a worker (ids and paths, never a monitor)."""

    spec: FleetSpec
    source: object  # CsvDirectory or ParquetRecords
    shard: int
    assets: tuple
    out: str
    buckets: int
    on_bad_record: str = "stop"  # or "skip": a record that cannot be used leaves its asset out, with the reason


def default_shard_size(count: int, workers: int) -> int:
    """``ceil(count / (4 * workers))`` within ``[1, 1000]``: four shards per worker balance the load.

    >>> default_shard_size(10_000, 2), default_shard_size(6, 2), default_shard_size(10**6, 2)
    (1000, 1, 1000)
    """
    return min(MAX_SHARD, max(1, math.ceil(count / (4 * max(workers, 1)))))


def shard_assets(assets: Sequence[str], size: int) -> list[tuple]:
    """Sorted ids in consecutive shards of ``size`` (the last one shorter): the same for the same ids.

    >>> shard_assets(["c", "a", "b"], 2)
    [('a', 'b'), ('c',)]
    """
    ids = sorted(assets)
    return [tuple(ids[i:i + size]) for i in range(0, len(ids), size)]


def plan(spec: FleetSpec, source, out: str | Path, *, shard_size: int, buckets: int = BUCKETS,
         on_bad_record: str = "stop") -> list[Task]:
    """The tasks of a run: one per shard of the source's sorted asset ids."""
    out = str(Path(out).resolve())
    return [Task(spec, source, i, ids, out, buckets, on_bad_record)
            for i, ids in enumerate(shard_assets(source.assets(), shard_size))]


def run_shard(task: Task) -> dict:
    """Run one shard (on a worker, or in this process) and write its tables; return its small summary."""
    start, cpu = time.perf_counter(), time.process_time()
    built, new = monitor_for(task.spec)
    skipped = {}
    records = task.source.read(task.assets, built.signals,
                               skip=skipped.__setitem__ if task.on_bad_record == "skip" else None)
    result = built.monitor.run(records, on_bad_record=task.on_bad_record)
    skipped.update(result.skipped)
    rows, files = write_shard(result, task.out, task.shard, task.buckets)
    return {"shard": task.shard, "assets": len(task.assets), "files": files, "skipped": dict(sorted(skipped.items())),
            "assets_with_alarm": int(len(set(result.alarms["asset"].tolist()))), "rows": rows,
            "seconds": time.perf_counter() - start, "cpu_seconds": time.process_time() - cpu,
            "built_monitor": new, "worker": f"{socket.gethostname()}:{os.getpid()}"}


def run_fleet(spec: FleetSpec, sources, out: str | Path, *, scheduler=None, workers: int = WORKERS,
              shard_size: int | None = None, buckets: int = BUCKETS,
              progress: Callable[[int, int], None] | None = None, notes: dict | None = None,
              resume: bool = False, on_bad_record: str = "stop", page: bool = True, truth: dict | None = None) -> dict:
    """Monitor every asset of ``sources`` and write the tables to Parquet under ``out``; return the summary.

    Parameters
    ----------
    spec : FleetSpec
        The job (model, failure values, laws, noise, detection, monitor settings, seed).
    sources : path or source
        A directory of CSV files (one per asset, the id is the file name) or a Parquet file with an
        ``asset`` column (:func:`~bgphm.fleet.sources.open_source`).
    out : path
        Output directory: ``alarms/``, ``estimates/``, ``rul/`` and ``residuals/`` (Parquet,
        partitioned by asset bucket), ``summary.json``, ``index.html`` and ``manifest.json``
        (:mod:`bgphm.fleet.outdir`).  One run at a time writes there (a second is refused while the
        first lives); shards are staged and the tables replace a previous run's whole at the end,
        ``manifest.json`` last.
    scheduler : None, "serial", str or distributed.Client
        None: a local Dask cluster of ``workers`` processes (one thread each); ``"serial"`` (or
        ``workers=0``): every shard in this process, without Dask; ``"tcp://host:port"``: the
        scheduler of a running cluster (the workers must see the records and ``out`` at the same
        paths); a ``distributed.Client``: its cluster (left open).
    workers : int
        Worker processes of the local cluster (0: the serial run).
    shard_size : int, optional
        Assets per task (default :func:`default_shard_size`).  The results do not depend on it.
    buckets : int
        Partitions of each table.
    progress : callable, optional
        ``progress(assets_done, assets_total)`` after each shard.
    notes : dict, optional
        Written into ``summary.json`` as they are (e.g. how the noise was calibrated).
    on_bad_record : {"stop", "skip"}
        A record that cannot be used (unreadable, a column without a value, a stuck sensor, too
        short): "stop" ends the run with its error, naming the file or asset; "skip" leaves the asset
        out and lists it with the reason in ``summary.json`` (``skipped``).
    resume : bool
        Go on with the interrupted run staged under ``out``: the same spec, records, shards and
        buckets are required, and its finished shards (their files checked against their SHA-256)
        are kept; the tables equal those of an uninterrupted run, bit for bit.
    page : bool
        Write the overview page ``index.html`` (:mod:`bgphm.fleet.page`), built from the tables this
        process reads back whole; False removes a previous run's (it would show other tables).
    truth : dict, optional
        Asset -> ``{"eol": s}`` (the true end of life, None for an asset that does not fail): the RUL
        predictions are scored against it (:meth:`~prognosis.fleet.FleetResult.scores`) into
        ``summary["truth"]`` (with ``not_in_fleet``, the truths of no asset of the run).

    Returns
    -------
    dict
        What ``summary.json`` holds: assets, assets with an alarm, rows per table, shards, seconds
        (wall, and summed over tasks), the monitors the tasks built (one per worker process, none
        where a process kept it from an earlier run of the same spec), the spec, and the units
        (time, signals, parameters, residuals: :func:`bgphm.units.units_of`).

    Examples
    --------
    Two RLC circuits, one with a resistance drifting up from 0.5 s, in this process:

    >>> import tempfile, pathlib, numpy as np
    >>> from bondgraph import simulate
    >>> from bondgraph.library import rlc_circuit
    >>> from bgphm.files import csv_text
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> t = np.linspace(0.0, 3.0, 3001)
    >>> for name, drift in [("ok", None), ("worn", lambda t: 10.0 + 4.0 * max(0.0, t - 0.5))]:
    ...     run = simulate(rlc_circuit(), (0.0, 3.0), {"V": lambda t: 5 + np.sin(7 * t)}, t_eval=t,
    ...                    parameters={"R": drift} if drift else {})
    ...     _ = (folder / f"{name}.csv").write_text(csv_text(run.record()))
    >>> spec = FleetSpec("rlc", {"R": 20.0}, noise_std={"ARR_J1": 1e-3}, laws=["linear"], dt=0.01,
    ...                  n_particles=200, detection={"margin": 0.01}, integrals="keep", arrs=["ARR_J1"])
    >>> summary = run_fleet(spec, folder, folder / "out", workers=0)
    >>> summary["assets"], summary["assets_with_alarm"], summary["shards"]
    (2, 1, 2)
    >>> from bgphm.fleet import read_fleet
    >>> rul = read_fleet(folder / "out").rul
    >>> sorted(set(rul["asset"])), bool(abs(rul["t"][-1] + rul["p50"][-1] - 3.0) < 0.2)
    (['worn'], True)
    """
    _check_counts(workers, shard_size, buckets)
    if on_bad_record not in ("stop", "skip"):
        raise UsageError(f"on_bad_record must be 'stop' or 'skip', got {on_bad_record!r}")
    source = open_source(sources)
    serial = scheduler == SERIAL or (scheduler is None and workers == 0)
    assets = source.assets()
    size = shard_size or default_shard_size(len(assets), workers)
    if not serial:  # a bad spec fails here, once, before a cluster starts (a serial run builds it in its first shard)
        monitor_for(spec)
    out = Path(out)
    with locked(out):
        output = Output(out)
        tasks = plan(spec, source, output.staging, shard_size=size, buckets=buckets, on_bad_record=on_bad_record)
        facts = {"spec": spec.as_dict(), "records": source.describe(), "buckets": buckets,
                 "on_bad_record": on_bad_record, "shards": [list(task.assets) for task in tasks]}
        finished = output.start(facts, resume=resume)
        start = time.perf_counter()
        done = list(finished.values())

        def report(summary: dict) -> None:
            output.finished(summary)
            done.append(summary)
            if progress is not None:
                progress(sum(s["assets"] for s in done), len(assets))

        todo = [task for task in tasks if task.shard not in finished]
        if serial:
            where = SERIAL
            for task in todo:
                report(run_shard(task))
        else:
            where = _run_dask(todo, scheduler, workers, report) if todo else SERIAL
        summary = _summary(spec, source, done, where, size, buckets, time.perf_counter() - start, notes)
        summary["resumed_shards"] = len(finished)
        built, _ = monitor_for(spec)  # this process built it already (the check above, or the serial shards)
        summary["units"] = units_of(built.model, built.monitor.arrs)
        tables = _staged(output, done) if page or truth else None
        if truth:
            summary["truth"] = tables.scores(truth)
            summary["truth"]["not_in_fleet"] = sorted(set(truth) - set(assets))
        text = _page(tables, built, summary, facts) if page else None
        output.publish(summary, _manifest(facts, done, size), text)
    return summary


def _staged(output: Output, done: list):
    """The run's staged tables, read back and checked against their SHA-256."""
    return read_tables(output.staging, {path: digest for s in done for path, digest in s["files"].items()})


def _page(tables, built, summary: dict, facts: dict) -> str:
    """The overview page of the run, from its staged tables."""
    assets = [asset for shard in facts["shards"] for asset in shard]
    return fleet_page(tables, summary, assets=assets, units=summary["units"],
                      horizon=built.monitor.settings.rul_horizon, provenance=provenance(built.model))


def _manifest(facts: dict, done: list, size: int) -> dict:
    """What a reader checks the tables against: the settings, every shard's assets, rows and files."""
    shards = sorted(done, key=lambda s: s["shard"])
    return {"spec": facts["spec"], "records": facts["records"], "buckets": facts["buckets"], "shard_size": size,
            "assets": sum(len(a) for a in facts["shards"]),
            "shards": [{"shard": s["shard"], "assets": facts["shards"][s["shard"]], "rows": s["rows"],
                        "files": s["files"], "skipped": s["skipped"]} for s in shards]}


def _check_counts(workers, shard_size, buckets) -> None:
    for name, value, low in (("workers", workers, 0), ("shard_size", shard_size, 1), ("buckets", buckets, 1)):
        if value is None and name == "shard_size":
            continue
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise UsageError(f"{name} must be a whole number >= {low}, got {value!r}")
    if buckets > 1000:
        raise UsageError(f"buckets must be at most 1000 (files per shard and table), got {buckets}")


def _summary(spec, source, done, where, size, buckets, seconds, notes) -> dict:
    done = sorted(done, key=lambda s: s["shard"])
    rows = {name: sum(s["rows"].get(name, 0) for s in done) for name in TABLES}
    assets = sum(s["assets"] for s in done)
    task_seconds = sum(s["seconds"] for s in done)
    return {"records": source.describe(), "scheduler": where, "assets": assets,
            "assets_with_alarm": sum(s["assets_with_alarm"] for s in done), "rows": rows, "shards": len(done),
            "shard_size": size, "buckets": buckets, "wall_s": seconds, "task_s": task_seconds,
            "cpu_s": sum(s["cpu_seconds"] for s in done),
            "seconds_per_asset": seconds / assets if assets else None,
            "monitors_built": sum(bool(s["built_monitor"]) for s in done),
            "workers": sorted({s["worker"] for s in done}), "spec": spec.as_dict(),
            "skipped": {asset: why for s in done for asset, why in s["skipped"].items()},
            **({"notes": notes} if notes else {})}


# ------------------------------------------------------------------------------------------------ Dask

def require_dask() -> None:
    """Raise :class:`~bgphm.errors.MissingExtraError` now if a Dask run could not start (before any work)."""
    _distributed()


def _distributed():
    try:
        import dask
        import distributed
    except ImportError as error:
        raise MissingExtraError("a Dask run needs dask.distributed: pip install 'bondgraph-phm[dask]' "
                                "(or run in this process: workers=0, bgphm fleet --workers 0)") from error
    return dask, distributed


def _run_dask(tasks: list[Task], scheduler, workers: int, report: Callable[[dict], None]) -> str:
    """Submit every shard, report each as it completes; return where it ran."""
    dask, distributed = _distributed()
    with _client(dask, distributed, scheduler, workers) as (client, where):
        _check_malloc(client)
        futures = [client.submit(run_shard, task, pure=False) for task in tasks]
        try:
            for future in distributed.as_completed(futures):
                report(future.result())  # a shard's error is raised here, with its own type and message
        finally:
            client.cancel(futures)  # after an error or Ctrl-C, no shard goes on writing
    return where


@contextlib.contextmanager
def _client(dask, distributed, scheduler, workers: int) -> Iterator:
    if isinstance(scheduler, distributed.Client):
        yield scheduler, str(scheduler.scheduler.address)
        return
    if scheduler is not None:
        yield from _remote(distributed, str(scheduler))
        return
    with local_cluster(workers) as client:
        yield client, f"local cluster ({workers} workers)"


@contextlib.contextmanager
def local_cluster(workers: int = 2) -> Iterator:
    """A local Dask cluster as :func:`run_fleet` starts it; yields its ``distributed.Client``.

    ``workers`` processes of one thread each (the filter is vectorized: a thread per core is all it
    uses), without the nanny's malloc setting, the scheduler's HTTP server on a free port, and no
    worker log below CRITICAL (a failed shard's error reaches the driver, which raises it: a worker's
    log would repeat it with a traceback).
    """
    dask, distributed = _distributed()
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise UsageError(f"workers must be at least 1 for a Dask run, got {workers!r}")
    with _without_malloc_setting(dask), _workers_ignore_interrupts():
        # the scheduler's HTTP server on a free port (with None it still takes 8787, or warns that it is taken)
        cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                           dashboard_address=":0", silence_logs=logging.CRITICAL)
    with cluster, distributed.Client(cluster) as client:
        yield client


@contextlib.contextmanager
def _workers_ignore_interrupts() -> Iterator[None]:
    """Start worker processes with SIGINT ignored (they inherit it); this process keeps its own handler.

    Ctrl-C in a terminal reaches every process of its group: the workers printed a traceback each
    (67 lines for two workers), while the driver, which alone has something to say, stops the run and
    closes the cluster, printing one line.
    """
    try:
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread: signals are not ours to change
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@contextlib.contextmanager
def _without_malloc_setting(dask) -> Iterator[None]:
    """Start worker processes without ``MALLOC_TRIM_THRESHOLD_`` in their environment.

    Dask's nanny sets ``MALLOC_TRIM_THRESHOLD_=65536`` for its workers (config key
    ``distributed.nanny.pre-spawn-environ``).  glibc reads it when a process starts, and a fixed trim
    threshold also turns off its dynamic mmap threshold, so numpy arrays over 128 KiB are mmapped and
    page-faulted afresh at every filter step: in the prototype, this doubled the CPU time.  None
    removes the variable from the nanny's list.  The nanny also writes the list into this process's
    environment (a cluster started earlier here did), which spawned workers inherit: the variable is
    taken out of it while the workers start (it has no effect on this process, which started already).
    """
    saved = os.environ.pop(MALLOC, None)
    try:
        with dask.config.set({f"distributed.nanny.pre-spawn-environ.{MALLOC}": None}):
            yield
    finally:
        if saved is not None:
            os.environ[MALLOC] = saved


def _remote(distributed, address: str) -> Iterator:
    try:
        client = distributed.Client(address, timeout=CONNECT_TIMEOUT)
    except (OSError, ValueError, TypeError) as error:
        raise FleetError(f"scheduler {address}: cannot connect ({_one_line(error)})") from None
    with client:
        try:
            client.wait_for_workers(1, timeout=WORKER_TIMEOUT)
        except (TimeoutError, OSError):
            raise FleetError(f"scheduler {address}: no worker joined within {WORKER_TIMEOUT:g} s "
                             f"(start some with: dask worker {address})") from None
        yield client, address


def _check_malloc(client) -> None:
    """Warn when workers run with a fixed malloc trim threshold (remote ones started by a default nanny)."""
    settings = client.run(malloc_setting)
    fixed = sorted(address for address, value in settings.items() if value is not None)
    if fixed:
        warnings.warn(f"{len(fixed)} of {len(settings)} worker(s) run with {MALLOC}={settings[fixed[0]]} (set by "
                      "Dask's nanny), which can double the filter's CPU time; start them with "
                      f"DASK_DISTRIBUTED__NANNY__PRE_SPAWN_ENVIRON='{{\"{MALLOC}\": None}}' "
                      "(see docs/fleet.md)", FleetWarning, stacklevel=4)


def malloc_setting() -> str | None:
    """``MALLOC_TRIM_THRESHOLD_`` in this process's environment (run on each worker by the driver).

    A module function, not ``os.environ.get``: that bound method would pickle the driver's environment
    along with it and read that one on the worker.
    """
    return os.environ.get(MALLOC)


def _one_line(error: BaseException) -> str:
    return " ".join(str(error).split())
