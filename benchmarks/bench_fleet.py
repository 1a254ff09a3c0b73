"""Fleet benchmark: K torsion-bar assets from Parquet records to Parquet tables on a local Dask cluster.

The b-md case of ``examples/torsion_bar.py`` (b_Md growing as b_Md,n exp(0.05 (t - 10)) from
t = 10 s, failure at 0.45 N.m.s/rad, 100 s at 100 Hz) is simulated once, without noise; every asset
then gets its own encoder phase and sensor noise (``encoder(record, default_rng([i, 7]))`` and
``add_noise(..., NOISE, seed=i)`` for asset ``i``), and the K records go to one Parquet file with
an ``asset`` column (rows sorted by asset, a row group per 25 assets), which the workers read as a
user's would.  The
residual noise is calibrated on a separate healthy record (``noise_margin(..., k=1)``, never from
the truth).  The job: the named candidate b_Md failing at 0.45, law ``exponential`` with the
case's absolute process noise (as HealthMonitor's named preset), N = ``--particles``, dt = 0.1 s,
a RUL every 10 filter steps, horizon 200 s.

What is measured, all in one run of this script (one JSON line with ``--json``):

* ``wall_s``: ``run_fleet`` on a local cluster of ``--workers`` processes that it starts itself,
  from the records on disk to the Parquet tables (cluster start and the workers' monitors included);
  ``seconds_per_asset`` = wall_s / K;
* ``dask_speedup``: the serial in-process ``run_fleet`` (one shard of K) on the same records,
  against that Dask run;
* ``deterministic_across_sharding``: the tables of the layouts 1 x K (the serial run), 2 x K/2 and
  10 x K/10 (Dask; the default run when its shards are K/10), read back with ``read_fleet``,
  compared bitwise, every column of every table;
* ``particle_steps_per_s``: filter particle-steps of the Dask run (filter steps from each asset's
  alarm to the end of its record, times N) over the CPU seconds of its tasks summed over workers;
* ``filter_particle_steps_per_s_per_core``: ``FleetFilter.step`` and the mean estimates alone on
  1000 rows x N particles in a fresh process (in the benchmark's own process, after the Dask runs,
  the same steps took up to 1.8 times as long);
* ``rul_ms_per_asset_prediction``: ``FleetMonitor.run`` of ``--rul-assets`` records with a RUL at
  every filter step, minus the same run with a RUL only at the first step, over the extra
  predictions;
* ``memory_per_asset_kb``: peak RSS growth of ``FleetMonitor.run`` (records read from the Parquet
  file; the peak counted from just before the run) in a fresh process at M and M/2 assets
  (M = min(K, ``--memory-assets``)), the difference over M/2; ``memory_fixed_mb`` is what remains at
  M.  Up to the 1000 assets the monitor filters together, this includes the block's observations
  and step arrays (bounded by the block); beyond, only the result tables grow
  (``--memory-assets 2000`` at K >= 2000 shows it);
* ``ra_vs_single_asset``: mean RA of the fleet minus that of ``HealthMonitor`` (named preset, same
  records, same settings) over the first ``--ra-assets`` assets, RA as the example computes it
  (predictions from t = 52 s to before the end of life); ``speedup_vs_health_monitor`` is the
  seconds per asset of that HealthMonitor loop over those of the serial fleet run (one process each);
* ``stream_us_per_sample``: ``FleetMonitor.update`` on one asset in a fresh process, 10^5 samples
  (1000 s at 100 Hz) in micro-batches of 100 samples (1 s), on a slower b_Md drift (gamma 0.05 / 8
  from t = 280 s, failure at t = 999 s) so that the alarm comes mid-stream and the filter runs on
  the rest; ``stream_rss_growth_pct`` over the second half of the samples.  The stream runs three
  times, each in a fresh process: the timings are the mean, ``..._worst`` the slowest run (they
  move by about 10 % between runs on a shared machine);
* ``stream_single_us_per_sample``: the same stream pushed one sample per ``update``, and
  ``stream_single_to_batch_ratio`` its cost per sample over the micro-batches' (whole stream, and
  before and after the alarm).

    python benchmarks/bench_fleet.py                      # K = 1000, a table
    python benchmarks/bench_fleet.py --assets 1000 --json # one JSON line
    python benchmarks/bench_fleet.py --assets 100 --keep /tmp/fleet   # keep the records and the tables

Targets (this 2-core machine): 10^4 assets under 15 minutes on 2 workers, <= 90 ms per
asset at K = 1000; the filter with mean estimates at >= 10 M particle-steps/s per core; RUL <= 0.5 ms
per asset-prediction; memory <= 100 KB per asset beside a fixed <= 1 GB; streaming <= 20 us per
sample at 10^5 samples with RSS growth < 1 % over the last half (also after the alarm, and
per-sample pushes at most 25x the micro-batches' cost per sample); bitwise identical tables under
sharding; RA within 0.5 % of HealthMonitor's.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import dataclasses
import json
import math
import multiprocessing
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))

import torsion_bar as tb  # noqa: E402  (examples/, put on the path above)

from bgphm.errors import MissingExtraError  # noqa: E402
from bgphm.fleet import FleetSpec, ParquetRecords, local_cluster, read_fleet, run_fleet  # noqa: E402
from bgphm.fleet.engine import require_dask  # noqa: E402
from bgphm.fleet.sources import pyarrow_modules  # noqa: E402
from bgphm.fleet.spec import build  # noqa: E402
from diagnosis import derive_arrs  # noqa: E402
from diagnosis.detection import noise_margin  # noqa: E402
from diagnosis.records import add_noise, as_record  # noqa: E402
from prognosis import HealthMonitor  # noqa: E402
from prognosis.degradation import ExponentialDegradation  # noqa: E402
from prognosis.fleet import FleetFilter  # noqa: E402
from prognosis.fleet.fleet_monitor import BLOCK  # noqa: E402
from prognosis.fleet.results import TABLES  # noqa: E402
from prognosis.hypotheses import Hypothesis, rate_prior  # noqa: E402
from prognosis.metrics import mean_relative_accuracy, relative_accuracy  # noqa: E402
from prognosis.health_monitor import filter_stride  # noqa: E402
from prognosis.observation import observation_model  # noqa: E402
from prognosis.random_streams import AssetStreams  # noqa: E402

CASE = tb.CASES["b-md"]
# the stream's case: the same law 8x slower from t = 280 s, failing at t = 999 s, so that 10^5 samples
# (1000 s at 100 Hz) hold a long healthy stretch, the alarm, and a long run of the filter
SLOW = dataclasses.replace(CASE, name="b-md-slow", gamma=CASE.gamma / 8, onset=280.0)
CALIBRATION_SEED = 10**7  # the healthy record that calibrates the noise: no asset has this seed
STREAM_SEED = 10**7 + 1
ROW_GROUP_ASSETS = 25  # assets per Parquet row group: a worker's read skips the groups of other assets
SIGNALS = ("omega_m", "omega_Ld", "tau_m", *tb.ANTIDERIVATIVES.values())
MODEL = """from bondgraph.library import torsion_bar_monitorable

model = torsion_bar_monitorable  # the monitorable part, as examples/torsion_bar.py derives its ARR from
"""
STREAM_SAMPLES, STREAM_BATCH = 100_000, 100
STREAM_RUNS = 3  # the stream's timings move by about 10 % between runs on a shared machine: mean and worst
FILTER_ROWS, FILTER_STEPS = 1000, 20


def log(message: str) -> None:
    print(f"[bench_fleet {time.strftime('%H:%M:%S')}] {message}", file=sys.stderr, flush=True)


def rss_bytes() -> int:
    """This process's resident set size now."""
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def busy_cpu_seconds() -> float:
    """CPU seconds the whole machine spent busy since boot (every process; /proc/stat, idle and iowait out)."""
    with open("/proc/stat") as stat:
        fields = [int(v) for v in stat.readline().split()[1:]]
    return (sum(fields) - fields[3] - fields[4]) / os.sysconf("SC_CLK_TCK")


def reset_peak_rss() -> None:
    """Start this process's peak RSS (VmHWM) again from its RSS now (Linux >= 4.0: /proc/self/clear_refs)."""
    with open("/proc/self/clear_refs", "w") as refs:
        refs.write("5")


def peak_rss_bytes() -> int:
    """This process's peak resident set size since the last :func:`reset_peak_rss` (VmHWM)."""
    with open("/proc/self/status") as status:
        line = next(line for line in status if line.startswith("VmHWM:"))
    return int(line.split()[1]) * 1024


def in_fresh_process(function, *args):
    """``function(*args)`` in a new (spawned) process: its own heap, its own peak RSS."""
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(max_workers=1, mp_context=context) as pool:
        return pool.submit(function, *args).result()


# ------------------------------------------------------------------------------------------------ the job

@dataclasses.dataclass
class Setup:
    """The simulated case, the ARR, the calibrated noise and the fleet job."""

    scenario: tb.Scenario
    arr: object
    noise: float
    detection: dict
    spec: FleetSpec


def setup(folder: Path, particles: int) -> Setup:
    """Simulate the b-md case once (no noise), calibrate the residual noise, write the model file, the spec."""
    scenario = tb.simulate_case(CASE)
    _, monitorable = CASE.bond_graphs()
    arr = next(a for a in derive_arrs(monitorable, complete=False, integrals="keep") if a.junction == "1_1")
    calibration = noisy(scenario.clean_nominal, CALIBRATION_SEED)
    options = {"antiderivatives": tb.ANTIDERIVATIVES}
    noise = noise_margin(arr, calibration, k=1.0, **options)
    detection = {**options, "margin": tb.MARGIN_SIGMAS * noise, "persistence": tb.PERSISTENCE}
    model = folder / "torsion_bar_model.py"
    model.write_text(MODEL)
    spec = FleetSpec(str(model), {CASE.candidate: CASE.theta_fail}, noise_std={arr.name: noise}, detection=detection,
                     laws=[CASE.law], candidates=[CASE.candidate], arrs=[arr.name], integrals="keep",
                     dt=tb.DT_FILTER, n_particles=particles, rul_every=10, horizon=200.0,
                     process_noise=CASE.process_noise, seed=0)
    return Setup(scenario, arr, noise, detection, spec)


def noisy(clean: dict, seed: int):
    """A record as the sensors give it: the encoders at their own phase, noise on speeds and torque."""
    return add_noise(as_record(tb.encoder(clean, np.random.default_rng([seed, 7]))), tb.NOISE, seed=seed)


def asset_ids(count: int) -> list[str]:
    width = len(str(max(count - 1, 1)))
    return [f"m{i:0{width}d}" for i in range(count)]


def write_records(path: Path, scenario: tb.Scenario, count: int) -> dict:
    """Every asset's noisy record into one Parquet file (sorted by asset); its size and the time taken."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    start = time.perf_counter()
    ids = asset_ids(count)
    schema = pa.schema([("asset", pa.string()), ("t", pa.float64()), *[(s, pa.float64()) for s in SIGNALS]])
    with pq.ParquetWriter(path, schema) as writer:
        for first in range(0, count, ROW_GROUP_ASSETS):
            group = range(first, min(first + ROW_GROUP_ASSETS, count))
            records = [noisy(scenario.clean_degraded, i) for i in group]
            n = records[0].t.size
            columns = {"asset": pa.array(np.repeat(np.array([ids[i] for i in group], dtype=object), n), pa.string()),
                       "t": np.concatenate([r.t for r in records]),
                       **{s: np.concatenate([r[s] for r in records]) for s in SIGNALS}}
            writer.write_table(pa.table(columns, schema=schema), row_group_size=len(group) * n)
    return {"records_write_s": time.perf_counter() - start, "records_mb": path.stat().st_size / 2**20,
            "samples_per_record": int(scenario.clean_degraded["t"].size)}


# ------------------------------------------------------------------------------------------------ fleet runs

def timed_run(spec: FleetSpec, records: Path, out: Path, **options) -> dict:
    """``run_fleet`` timed from the call to its return; its summary with ``wall_s`` and ``machine_busy_s``.

    ``machine_busy_s``: CPU seconds every process of the machine spent meanwhile (this run's and others').
    """
    busy, start = busy_cpu_seconds(), time.perf_counter()
    summary = run_fleet(spec, records, out, **options)
    summary["wall_s"] = time.perf_counter() - start
    summary["machine_busy_s"] = busy_cpu_seconds() - busy
    return summary


def identical(a, b) -> bool:
    """Bitwise equality of every column of every table of two fleet results (NaN equal to NaN)."""
    for name in TABLES:
        ta, tb_ = a.table(name), b.table(name)
        if set(ta) != set(tb_):
            return False
        for column, x in ta.items():
            y = tb_[column]
            if x.dtype == object or y.dtype == object:
                if x.tolist() != y.tolist():
                    return False
            elif x.dtype != y.dtype or x.shape != y.shape or x.tobytes() != y.tobytes():
                return False
    return True


def sharding(spec: FleetSpec, records: Path, work: Path, count: int, workers: int, dask_run: dict,
             serial_out: Path, dask_out: Path) -> dict:
    """Tables of 1 x K (serial), 2 x K/2 and 10 x K/10 (Dask): identical bitwise?"""
    layouts = {f"1x{count}": serial_out}
    sizes = [math.ceil(count / 2), math.ceil(count / 10)]
    todo = [size for size in sizes if size != dask_run["shard_size"]]
    for size in sizes:
        if size == dask_run["shard_size"]:
            layouts[f"{math.ceil(count / size)}x{size}"] = dask_out  # the timed Dask run has this layout
    if todo:
        with local_cluster(workers) as client:
            for size in todo:
                out = work / f"out-shards-{size}"
                log(f"sharding: {math.ceil(count / size)} shards of {size} on Dask")
                run_fleet(spec, records, out, scheduler=client, shard_size=size)
                layouts[f"{math.ceil(count / size)}x{size}"] = out
    results = {name: read_fleet(out) for name, out in layouts.items()}
    first = next(iter(results.values()))
    assets = len(set(first.table("estimates")["asset"].tolist()))
    same = all(identical(first, other) for other in results.values())
    return {"deterministic_across_sharding": bool(same and assets == count),
            "sharding_layouts": {name: "serial" if out == serial_out else "dask" for name, out in layouts.items()},
            "sharding_assets_with_estimates": assets}


def particle_steps(result, t: np.ndarray, particles: int, report_every: int) -> dict:
    """Filter steps of every asset (from its alarm to the end of its record) and the particle-steps.

    Every asset's record has the same time grid ``t``; the count is checked against the last
    reported step of each asset.
    """
    stride = filter_stride(t, tb.DT_FILTER)
    alarms = result.alarms
    first = {}
    for asset, when in zip(alarms["asset"].tolist(), alarms["t"]):
        first.setdefault(asset, float(when))
    estimates = result.estimates
    last = {}
    for asset, step in zip(estimates["asset"].tolist(), estimates["step"].tolist()):
        last[asset] = step
    steps, consistent = 0, True
    for asset, when in first.items():
        k = int(np.searchsorted(t, when - 1e-9))
        mine = len(range(k, t.size, stride))
        steps += mine
        consistent &= asset in last and last[asset] < mine <= last[asset] + report_every
    return {"filter_steps": steps, "particle_steps": steps * particles, "filter_steps_consistent": bool(consistent),
            "assets_with_alarm": len(first)}


def fleet_ra(result, assets: list) -> list[float]:
    """RA of each asset's fleet RUL means as examples/torsion_bar.py computes it (t in [after, eol))."""
    out = []
    for asset in assets:
        rul = result.for_asset(asset).rul
        keep = (rul["t"] >= CASE.after) & (rul["t"] < CASE.eol)
        out.append(float(mean_relative_accuracy(relative_accuracy(CASE.eol - rul["t"][keep], rul["mean"][keep]))))
    return out


def health_monitor_ra(s: Setup, records: Path, assets: list, particles: int) -> dict:
    """HealthMonitor with the named preset on the same records: RA per asset and seconds per asset."""
    settings = tb.tuning(CASE, "named", s.noise, particles)
    ra, seconds = [], 0.0
    for i, (asset, record) in enumerate(ParquetRecords(str(records)).read(assets, list(SIGNALS))):
        monitor = HealthMonitor(s.arr, CASE.candidate, CASE.degradation_model(), theta_fail=CASE.theta_fail,
                                dt=tb.DT_FILTER, n_particles=particles, detection=s.detection, seed=i, rul_every=10,
                                theta_bounds=CASE.theta_bounds, **settings)
        start = time.perf_counter()
        result = monitor.run(record, workers=1)
        seconds += time.perf_counter() - start
        ra.append(result.metrics(CASE.truth, lambda t: CASE.gamma, eol=CASE.eol, after=CASE.after)["ra"])
    return {"ra": ra, "seconds_per_asset": seconds / len(assets)}


# ------------------------------------------------------------------------------------------------ parts alone

def filter_speed(s: Setup, particles: int) -> dict:
    """``FleetFilter.step`` plus the mean estimates on 1000 rows: particle-steps per second.

    Each row gets the measurement and point values of the degraded record at t = 60 s, theta starting
    in [b_Md,n, 3 b_Md,n] and the rate prior of the named hypothesis.
    """
    evaluation = s.arr.evaluate(noisy(s.scenario.clean_degraded, 0), **s.detection)
    k = int(np.searchsorted(evaluation.t, 60.0))
    hypothesis = Hypothesis(CASE.candidate, CASE.law, CASE.theta_fail, CASE.theta_n)
    pf = FleetFilter([ExponentialDegradation(CASE.process_noise)], [[observation_model(s.arr, CASE.candidate)]],
                     noise_std=[s.noise], n_particles=particles, dt=tb.DT_FILTER, streams=AssetStreams(0))
    rates = rate_prior(hypothesis, tb.DT_FILTER, particles, np.random.default_rng(0))
    every = np.ones(FILTER_ROWS)
    rows = pf.add(list(range(FILTER_ROWS)), hypothesis=np.zeros(FILTER_ROWS, int), lo=CASE.theta_n * every,
                  hi=3 * CASE.theta_n * every, rates=np.broadcast_to(rates, (FILTER_ROWS, 1, particles)),
                  process_noise=CASE.process_noise * every)
    y = np.full((FILTER_ROWS, 1), -evaluation.residual[k])
    points = [[np.full(FILTER_ROWS, p[k]) for p in evaluation.points]]
    pf.step(y, points, rows=rows)  # compiles nothing, but the first step pays page faults
    best = math.inf
    for _ in range(3):
        start = time.perf_counter()
        for _ in range(FILTER_STEPS):
            pf.step(y, points, rows=rows)
            pf.theta_mean(rows), pf.gamma_mean(rows)
        best = min(best, time.perf_counter() - start)
    return {"filter_particle_steps_per_s_per_core": FILTER_ROWS * particles * FILTER_STEPS / best,
            "filter_rows": FILTER_ROWS, "filter_ms_per_step": best / FILTER_STEPS * 1e3}


def rul_cost(spec: FleetSpec, records: Path, count: int) -> dict:
    """ms per asset-prediction: a run with a RUL at every step minus one with a RUL at the first step only."""
    ids = ParquetRecords(str(records)).assets()[:count]
    runs = {}
    for name, every in (("every", 1), ("first", 10**9)):
        monitor = build(dataclasses.replace(spec, rul_every=every, report_every=10)).monitor
        held = list(ParquetRecords(str(records)).read(ids, list(SIGNALS)))  # reading is not timed
        best, rows = math.inf, 0
        for _ in range(2):
            start = time.perf_counter()
            rows = monitor.run(held).rows("rul")
            best = min(best, time.perf_counter() - start)
        runs[name] = (best, rows)
    extra = runs["every"][1] - runs["first"][1]
    return {"rul_ms_per_asset_prediction": (runs["every"][0] - runs["first"][0]) / extra * 1e3,
            "rul_assets": len(ids), "rul_predictions": extra}


def monitor_memory(records: str, spec: FleetSpec, ids: list) -> dict:
    """In a fresh process: peak RSS growth of ``FleetMonitor.run`` over the assets ``ids`` of the file.

    The records are read from the Parquet file while the monitor runs (as a worker reads them); the
    peak is counted from just before the run (what the imports and the build took is not).
    """
    built = build(spec)
    source = ParquetRecords(records)
    before = rss_bytes()
    reset_peak_rss()
    result = built.monitor.run(source.read(ids, built.signals))
    return {"peak_growth_bytes": peak_rss_bytes() - before, "rul_rows": result.rows("rul")}


def memory(records: Path, spec: FleetSpec, count: int, total: int) -> dict:
    """Per-asset peak memory from fresh processes at ``count`` and ``count // 2`` assets, and the fixed part."""
    half, ids = count // 2, asset_ids(total)
    small = in_fresh_process(monitor_memory, str(records), spec, ids[:half])["peak_growth_bytes"]
    large = in_fresh_process(monitor_memory, str(records), spec, ids[:count])["peak_growth_bytes"]
    per_asset = (large - small) / (count - half)
    return {"memory_per_asset_kb": per_asset / 1024, "memory_fixed_mb": (large - per_asset * count) / 2**20,
            "memory_peak_growth_mb": large / 2**20, "memory_assets": [half, count], "memory_block_assets": BLOCK}


def stream_record(path: Path, samples: int) -> None:
    """The slow case's noisy record, its first ``samples`` samples, saved for the stream's process.

    Simulated here, so that the stream's process holds only the record and the monitor (its RSS
    growth is then a share of what streaming needs, not of a simulation's arrays).
    """
    scenario = tb.simulate_case(SLOW, t_end=(samples - 1) * tb.DT_RECORD + 1.0)
    record = noisy(scenario.clean_degraded, STREAM_SEED)
    if record.t.size < samples:
        raise RuntimeError(f"the slow case gave {record.t.size} samples, fewer than {samples}")
    np.savez(path, t=record.t[:samples], **{s: record[s][:samples] for s in SIGNALS})


def stream(spec: FleetSpec, path: str, batch: int) -> dict:
    """In a fresh process: ``FleetMonitor.update`` on one asset of the slow case, ``batch`` samples at a time."""
    with np.load(path) as saved:
        columns = {name: saved[name] for name in ("t", *SIGNALS)}
    samples = columns["t"].size
    monitor = build(spec).monitor
    asset = np.full(batch, "stream-0", dtype=object)
    took = np.empty(math.ceil(samples / batch))
    rss, alarm, rul_rows = {}, None, 0
    for i, start in enumerate(range(0, samples, batch)):
        stop = min(start + batch, samples)
        chunk = {"asset": asset[:stop - start], **{c: v[start:stop] for c, v in columns.items()}}
        began = time.perf_counter()
        out = monitor.update(chunk)
        took[i] = time.perf_counter() - began
        rul_rows += out.rows("rul")  # the rows are the caller's: counted, not kept
        if alarm is None and out.rows("alarms"):
            alarm = float(out.alarms["t"][0])
        if stop in (samples // 2, samples):
            rss[stop] = rss_bytes()
    state = monitor.checkpoint()["assets"][0]
    steps = int(state["rows"]["steps"][0]) if "rows" in state else 0
    alarm_sample = samples if alarm is None else int(round(alarm / tb.DT_RECORD))
    alarm_batch = alarm_sample // batch
    head = max(1, 1000 // batch)
    return {"stream_samples": samples, "stream_batch_samples": batch,
            "stream_us_per_sample": took.sum() / samples * 1e6,
            "stream_us_per_sample_first_1e3": took[:head].sum() / (head * batch) * 1e6,
            "stream_us_per_sample_last_1e3": took[-head:].sum() / (head * batch) * 1e6,
            "stream_us_per_sample_before_alarm": took[:alarm_batch].sum() / max(alarm_batch * batch, 1) * 1e6,
            "stream_us_per_sample_after_alarm": took[alarm_batch:].sum() / max(samples - alarm_batch * batch, 1) * 1e6,
            "stream_rss_growth_pct": (rss[samples] - rss[samples // 2]) / rss[samples // 2] * 100,
            "stream_rss_growth_mb": (rss[samples] - rss[samples // 2]) / 2**20, "stream_rss_mb": rss[samples] / 2**20,
            "stream_alarm_t": alarm, "stream_samples_before_alarm": alarm_sample,
            "stream_filter_steps": steps, "stream_rul_rows": rul_rows, "stream_eol_s": SLOW.eol}


def repeated_streams(runs: list[dict]) -> dict:
    """The figures of several runs of :func:`stream`: timings as their mean, with the worst run beside
    (``..._worst``); the rest from the first run (the same in every run)."""
    out = dict(runs[0])
    for key in runs[0]:
        if key.startswith("stream_us_per_sample"):
            values = [run[key] for run in runs]
            out[key], out[key + "_worst"] = float(np.mean(values)), float(np.max(values))
    out["stream_runs"] = len(runs)
    return out


# ------------------------------------------------------------------------------------------------ main

NOTES = {
    "wall_s": "run_fleet(spec, records.parquet, out, workers=W) with the local cluster it starts (start, monitor "
              "builds, reading, filtering, writing Parquet), timed around the call",
    "particle_steps_per_s": "filter particle-steps of the Dask run (steps from each asset's alarm to the end of "
                            "its record x N) / CPU seconds of its tasks summed over workers (process_time in "
                            "run_shard: reading, detection, filter, RUL, writing)",
    "memory_per_asset_kb": "peak RSS during FleetMonitor.run (VmHWM reset just before it) minus RSS before it, in a "
                           "fresh spawned process per count, records read from the Parquet file during the run; "
                           "(peak at M - peak at M/2) / (M/2); memory_fixed_mb = peak at M - M x per asset. Up to "
                           "memory_block_assets (the assets FleetMonitor.run filters together) this includes the "
                           "block's observations and step arrays; beyond, only the result tables grow",
    "rul_ms_per_asset_prediction": "FleetMonitor.run on records held in memory, rul_every=1 vs rul_every=1e9 "
                                   "(report_every=10 in both), best of 2 each, difference / extra RUL rows",
    "stream": "one asset, FleetMonitor.update with micro-batches of stream_batch_samples samples (1 s at 100 Hz), "
              "stream_runs runs each in a fresh process, the timings their mean (and _worst: the slowest run), "
              "slow b_Md drift; first/last 1e3: the first/last 10 batches; RSS from /proc/self/statm at half "
              "and at the end, in a fresh process",
    "dask_speedup": "wall time of the serial in-process run_fleet (workers=0, one shard of K) / wall_s",
    "dask_cpu_s": "CPU seconds of the Dask run's tasks summed over workers; dask_task_s: their wall seconds summed "
                  "(a task that had a core to itself has cpu ~ wall); dask_machine_busy_s, serial_machine_busy_s: "
                  "CPU seconds the whole machine was busy during each run (/proc/stat), other jobs included",
    "ra": "RA of the RUL mean over predictions with case.after <= t < case.eol, mean over the ra_assets; "
          "HealthMonitor with tuning(case, 'named', noise, N), seed = asset index, workers=1",
}


def parse(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--assets", type=int, default=1000, help="K, the number of assets (default 1000)")
    parser.add_argument("--json", action="store_true", help="print one JSON line")
    parser.add_argument("--workers", type=int, default=2, help="Dask worker processes (default 2)")
    parser.add_argument("--particles", type=int, default=500, help="N particles per asset (default 500)")
    parser.add_argument("--keep", type=Path, help="write the records and tables here and keep them (default: a "
                                                  "temporary directory under /tmp, removed at the end)")
    parser.add_argument("--ra-assets", type=int, default=20, help="assets compared with HealthMonitor (default 20)")
    parser.add_argument("--rul-assets", type=int, default=100, help="assets of the RUL cost runs (default 100)")
    parser.add_argument("--memory-assets", type=int, default=1000,
                        help="M: the memory is measured at min(K, M) and half that (default 1000)")
    args = parser.parse_args(argv)
    for name in ("assets", "workers", "particles", "ra_assets", "rul_assets", "memory_assets"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')} must be at least 1, got {getattr(args, name)}")
    if args.assets < 10:
        parser.error(f"--assets must be at least 10 (the 10 x K/10 layout), got {args.assets}")
    return args


def check_disk(folder: Path, count: int) -> None:
    """Refuse to start when the records (about 0.5 MB per asset) would not fit."""
    need = count * 0.55 * 2**20 + 2**30
    free = shutil.disk_usage(folder).free
    if free < need:
        raise SystemExit(f"bench_fleet: {folder} has {free / 2**30:.1f} GiB free; K = {count} needs about "
                         f"{need / 2**30:.1f} GiB for the records and tables")


def measure(args, work: Path) -> dict:
    count, n = args.assets, args.particles
    figures = {"assets": count, "workers": args.workers, "particles": n, "load_avg_start": os.getloadavg()}
    log("simulating the b-md case and calibrating the noise")
    s = setup(work, n)
    records = work / "records.parquet"
    log(f"writing {count} records to {records}")
    figures.update(write_records(records, s.scenario, count))
    log(f"Dask run: {count} assets on {args.workers} workers")
    dask_out = work / "out-dask"
    dask_run = timed_run(s.spec, records, dask_out, workers=args.workers)
    log(f"Dask run: {dask_run['wall_s']:.1f} s; serial run")
    serial_out = work / "out-serial"
    serial_run = timed_run(s.spec, records, serial_out, workers=0, shard_size=count)
    log(f"serial run: {serial_run['wall_s']:.1f} s")
    dask_result = read_fleet(dask_out)
    steps = particle_steps(dask_result, s.scenario.clean_degraded["t"], n, 10)
    figures.update(wall_s=dask_run["wall_s"], seconds_per_asset=dask_run["wall_s"] / count,
                   particle_steps_per_s=steps["particle_steps"] / dask_run["cpu_s"],
                   dask_speedup=serial_run["wall_s"] / dask_run["wall_s"], serial_wall_s=serial_run["wall_s"],
                   dask_cpu_s=dask_run["cpu_s"], dask_task_s=dask_run["task_s"],
                   dask_machine_busy_s=dask_run["machine_busy_s"], serial_machine_busy_s=serial_run["machine_busy_s"],
                   dask_shards=dask_run["shards"], dask_shard_size=dask_run["shard_size"],
                   particle_steps_per_s_wall=steps["particle_steps"] / dask_run["wall_s"], **steps)
    figures.update(sharding(s.spec, records, work, count, args.workers, dask_run, serial_out, dask_out))
    ra_ids = asset_ids(count)[:min(args.ra_assets, count)]
    log(f"HealthMonitor on {len(ra_ids)} assets")
    single = health_monitor_ra(s, records, ra_ids, n)
    fleet = fleet_ra(dask_result, ra_ids)
    figures.update(ra_vs_single_asset=float(np.mean(fleet) - np.mean(single["ra"])), ra_fleet=float(np.mean(fleet)),
                   ra_health_monitor=float(np.mean(single["ra"])), ra_assets=f"the first {len(ra_ids)} ({ra_ids[0]} to "
                   f"{ra_ids[-1]})", health_monitor_s_per_asset=single["seconds_per_asset"],
                   speedup_vs_health_monitor=single["seconds_per_asset"] / (serial_run["wall_s"] / count))
    log("the filter alone; the RUL cost")
    figures.update(in_fresh_process(filter_speed, s, n))  # no thread or heap left over from the Dask runs
    figures.update(rul_cost(s.spec, records, min(args.rul_assets, count)))
    log("memory in fresh processes")
    figures.update(memory(records, s.spec, min(args.memory_assets, count), count))
    log(f"streaming {STREAM_SAMPLES} samples of one asset, {STREAM_RUNS} times, each in a fresh process")
    stream_record(work / "stream.npz", STREAM_SAMPLES)
    figures.update(repeated_streams([in_fresh_process(stream, s.spec, str(work / "stream.npz"), STREAM_BATCH)
                                     for _ in range(STREAM_RUNS)]))
    log("the same stream pushed sample by sample")
    single = in_fresh_process(stream, s.spec, str(work / "stream.npz"), 1)
    for part in ("", "_before_alarm", "_after_alarm"):
        figures[f"stream_single_us_per_sample{part}"] = single[f"stream_us_per_sample{part}"]
        figures[f"stream_single_to_batch_ratio{part}"] = (single[f"stream_us_per_sample{part}"]
                                                          / figures[f"stream_us_per_sample{part}"])
    figures["load_avg_end"] = os.getloadavg()
    figures["notes"] = NOTES
    return figures


def main(argv=None) -> dict:
    args = parse(argv)
    try:
        require_dask()
        pyarrow_modules()
    except MissingExtraError as error:
        raise SystemExit(f"bench_fleet: {error}") from None
    if args.keep is not None:
        args.keep.mkdir(parents=True, exist_ok=True)
    work = args.keep.resolve() if args.keep is not None else Path(tempfile.mkdtemp(prefix="bench_fleet-", dir="/tmp"))
    try:
        check_disk(work, args.assets)
        figures = measure(args, work)
    finally:
        if args.keep is None:
            shutil.rmtree(work, ignore_errors=True)
    if args.json:
        print(json.dumps(figures))
    else:
        for key, value in figures.items():
            if key != "notes":
                print(f"{key:40s} {value:.4g}" if isinstance(value, float) else f"{key:40s} {value}")
    return figures


if __name__ == "__main__":
    main()
