"""``bgphm fleet``: many assets' records to Parquet tables (:func:`bgphm.fleet.run_fleet`)."""

from __future__ import annotations

from bgphm.errors import EXIT_OK
from bgphm.files import check_output, input_files
from bondgraph.errors import SettingError
from diagnosis import pooled_calibration
from prognosis import filter_step, rul_horizon

from ._inputs import (
    detection_settings,
    read_fleet_truth,
    what_can_fail,
)
from ._outputs import fmt
from ._progress import Progress, fleet_progress

__all__ = ["fleet_truth_line", "run"]


def run(args, progress: Progress) -> int:
    """``bgphm fleet``: detection, estimation and RUL for every asset of a fleet, to Parquet; returns 0.

    RECORDS is a directory of CSV files (one per asset, the asset id is the file name) or a Parquet
    file with an ``asset`` column.  The residual noise and the detection margins are calibrated on the
    first ``--calibrate`` seconds of the first ``--calibrate-assets`` records (by asset id): the median
    over them, per ARR, serves every asset.  The assets then run in shards on a local Dask cluster
    (``--workers``), on a running one (``--scheduler``), or in this process (``--workers 0``), through
    :func:`bgphm.fleet.run_fleet`, which writes the tables ``alarms/``, ``estimates/``, ``rul/`` and
    ``residuals/``, ``summary.json`` (with the units), the overview page ``index.html``
    (:mod:`bgphm.fleet.page`; not with ``--no-page``) and ``manifest.json`` under ``--out``.  Progress
    goes to stderr by assets done.
    """
    from bgphm.fleet import FleetSpec, model_reference, open_source, run_fleet
    from bgphm.fleet.engine import WORKERS, require_dask
    from bgphm.fleet.outdir import PAGE
    from prognosis.fleet.results import TABLES
    from bgphm.fleet.sources import pyarrow_modules

    pyarrow_modules()  # the missing extra named before any work
    if args.workers is None:
        args.workers = WORKERS
    if args.scheduler is not None or args.workers > 0:
        require_dask()
    source = open_source(args.records)
    # --resume goes on in the run's own --out: it is not empty, and needs no --force
    out = check_output(args.out, kind="directory", inputs=input_files(args.model) + source.inputs(),
                       force=args.force or args.resume)
    detection = detection_settings(args)
    truth = read_fleet_truth(args.truth) if args.truth is not None else None
    spec, arrs, failures, candidates, laws = what_can_fail(args, progress)
    assets = source.assets()
    progress(f"{len(assets)} assets in {source.describe()}")
    calibrated = assets[:args.calibrate_assets]
    signals = list(dict.fromkeys(s for arr in arrs for s in arr.signals))
    try:
        pooled, first = pooled_calibration(arrs, source.read(calibrated, signals), detection)
        dt = filter_step(first, detection.window, args.dt)
        rul_horizon(dt, args.horizon, args.particles, len(failures) * len(laws))
    except SettingError as exc:
        raise exc.within("records: ") if exc.setting == "calibrate" else exc from None
    calibration = {"assets": list(calibrated), "until": args.calibrate, "noise_std": pooled.noise_std,
                   "margin": pooled.margin}
    for name, why in pooled.undecided.items():
        progress(f"{name}: undecided, left out ({why})")
    for name in pooled.noise_std:
        progress(f"{name}: residual noise {pooled.noise_std[name]:.3g}, margin {pooled.margin[name]:.3g} (median "
                 f"over {len(calibrated)} record(s), t <= {args.calibrate:g} s)")
    detection = pooled.options(detection)
    job = FleetSpec(model_reference(args.model), failures, noise_std=calibration["noise_std"], detection=detection,
                    laws=laws, candidates=candidates, arrs=decided_arrs(args.arr, arrs, pooled.undecided),
                    integrals=args.integrals, dt=dt, n_particles=args.particles, rul_every=args.rul_every,
                    horizon=args.horizon, healthy_until=args.calibrate, seed=args.seed)
    where = args.scheduler or ("this process" if args.workers == 0 else f"a local cluster of {args.workers} workers")
    progress(f"monitoring {len(assets)} assets ({where}): {len(laws)} law(s) per candidate, {args.particles} "
             f"particles each, dt = {dt:g} s")
    summary = run_fleet(job, source, out, scheduler=args.scheduler, workers=args.workers,
                        shard_size=args.shard_size, progress=fleet_progress(progress), notes=calibration,
                        resume=args.resume, on_bad_record=args.on_bad_record, page=not args.no_page, truth=truth)
    for asset, why in list(summary["skipped"].items())[:5]:
        progress(f"skipped {asset}: {why}")
    print(f"{summary['assets']} assets, {summary['assets_with_alarm']} with an alarm, {summary['rows']['rul']} RUL "
          f"rows, in {summary['wall_s']:.1f} s ({1e3 * summary['seconds_per_asset']:.1f} ms per asset)")
    resumed = f" ({summary['resumed_shards']} of {summary['shards']} shards kept from the interrupted run)" \
        if args.resume else ""
    if summary["skipped"]:
        print(f"{len(summary['skipped'])} asset(s) skipped for a bad record, each with its reason in "
              f"{out / 'summary.json'} (skipped)")
    if truth is not None:
        print(fleet_truth_line(summary["truth"]))
    tables = ", ".join(str(out / name) for name in TABLES)
    page = "" if args.no_page else f", {out / PAGE} (open it in a browser)"
    print(f"wrote {tables} (Parquet), {out / 'summary.json'}{page} and {out / 'manifest.json'}{resumed}")
    return EXIT_OK


def fleet_truth_line(scored: dict) -> str:
    """One line: the fleet's predictions against the truth, pooled (``summary["truth"]``)."""
    pooled = scored["pooled"]
    if not pooled["predictions"]:
        return f"truth: no RUL prediction before an asset's end of life to score ({len(scored['assets'])} assets)"
    extra = "".join(f"; {len(scored[key])} {what}" for key, what in (("without_rul", "asset(s) with a truth but no "
                                                                      "RUL"), ("not_in_fleet", "truth(s) for no "
                                                                               "asset of the fleet"))
                    if scored.get(key))
    return (f"truth: {pooled['assets']} assets, {pooled['predictions']} predictions: mean RA "
            f"{fmt(pooled['mean_relative_accuracy'])} (per asset mean {fmt(pooled['asset_mean_relative_accuracy'])}, "
            f"worst {fmt(pooled['asset_worst_mean_relative_accuracy'])}), the 5-95 % band holds the truth at "
            f"{100 * pooled['coverage_90']:.0f} %, the median within 20 % at "
            f"{100 * pooled['within_alpha_share']:.0f} %{extra}")


def decided_arrs(chosen: str | None, arrs: list, undecided: dict) -> list | None:
    """The ARR names the assets are monitored with: the one chosen, or all (None) but those the calibration left
    out."""
    if chosen is not None:
        return [chosen]
    return [arr.name for arr in arrs if arr.name not in undecided] if undecided else None
