"""The qualitative study of Jha et al. (2016), section 6.4, as a sweep, and the path from their tuning to ours.

    python examples/torsion_bar_sweep.py [--case b-md] [--seeds 3] [--particles 500] [--out DIR]

Part 1 (section 6.4, Fig. 13-14): one parameter at a time around the paper's
tuning of Fig. 11a: the initial random-walk deviation sigma_xi,0, the gain P,
the reference RMAD v* and the band [gamma_l*, gamma_u*].

Part 2 (the named preset: candidate and law named, nothing taken from the truth): starting
from the paper's tuning, each change of the named preset is added in turn, so that the table
shows what each one buys: the residual noise calibrated on the nominal record, the theta
start that explains the alarm's residual, gamma held in the RUL prediction, the rate prior
from the failure value, and kernel smoothing of the rate (no band) with a 4x variance
inflation.  Part 1 moves the paper's values around its gamma* = 0.05, as the paper's study
does: it is an analysis around the truth, not a preset.

Every setting runs over ``--seeds`` noise seeds on one simulation; the figures
are the means.  Writes ``sweep.csv``, ``sweep.json`` and (with matplotlib)
``sweep.png`` to DIR; prints the table; progress goes to stderr.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import torsion_bar as example  # noqa: E402  (the sibling example script)

from bgphm.plotting import pyplot, save_figure, write_figures  # noqa: E402
from bgphm.runs import run_main  # noqa: E402
from prognosis import VarianceAdaptation  # noqa: E402

FIGURES = ("rmse_theta", "rmse_gamma", "rmad_gamma", "ra", "rmad_rul", "alpha_lambda_pass_rate",
           "prognostic_horizon_s")


def paper_study(case) -> list[tuple[str, str, dict]]:
    """(parameter, value label, overrides of the paper preset): section 6.4 one at a time."""
    tuning = case.paper_tuning
    scale = case.gamma / 0.05  # the values below are the paper's for gamma* = 0.05

    def adaptation(**change):
        settings = {"band": tuning["band"], "reference": tuning["reference"], "gain": tuning["gain"], **change}
        return {"adaptation": VarianceAdaptation(**settings)}

    rows = [("sigma_xi0", f"{s:g}", {"gamma_std": s * scale}) for s in (0.001, 0.005, 0.01, 0.02, 0.04)]
    rows += [("gain P", f"{p:g}", adaptation(gain=p)) for p in (1e-4, 1e-3, 5e-3, 1e-2)]
    rows += [("reference v*", f"{v:g}", adaptation(reference=v)) for v in (0.02, 0.05, 0.06, 0.10, 0.20)]
    rows += [("band", f"[{lo * scale:g}, {hi * scale:g}]", adaptation(band=(lo * scale, hi * scale)))
             for lo, hi in ((0.04, 0.06), (0.03, 0.07), (0.01, 0.09))]
    return rows


def ladder(case, residual_std: float) -> list[tuple[str, str, dict]]:
    """From the paper preset to the named preset, one change at a time (cumulative)."""
    paper, named = example.tuning(case, "paper", residual_std), example.tuning(case, "named", residual_std)
    steps = [("paper preset", {}),
             ("+ calibrated residual noise", {"noise_std": named["noise_std"]}),
             ("+ start from the alarm's residual", {"start": "residual"}),
             ("+ gamma held in the RUL prediction", {"prediction_walk": 0.0}),
             ("+ rate prior from the failure value", {"gamma0": named["gamma0"]}),
             ("+ kernel smoothing, 4x inflation (named)", {"adaptation": named["adaptation"],
                                                          "gamma_std": named["gamma_std"],
                                                          "inflation": named["inflation"]})]
    rows, settings = [], dict(paper)
    for label, change in steps:
        settings = {**settings, **change}
        rows.append(("paper -> named", label, dict(settings)))
    return rows


def sweep(case_name: str = "b-md", seeds: int = 3, n_particles: int | None = None, workers: int = 2,
          quiet: bool = False, parameters: list[str] | None = None) -> list[dict]:
    """Run every setting over ``seeds`` noise seeds; one row of mean figures per setting.

    ``parameters`` keeps only those groups (e.g. ``["band"]``); default: all.
    """
    case = example.CASES[case_name]
    scenario = example.simulate_case(case)
    detection = example.detection_setup(case, scenario, seed=0)[2]
    residual_std = detection["margin"] / example.MARGIN_SIGMAS
    plan = [(p, v, {**example.tuning(case, "paper", residual_std), **o}) for p, v, o in paper_study(case)]
    plan += ladder(case, residual_std)
    if parameters is not None:
        unknown = set(parameters) - {p for p, _, _ in plan}
        if unknown:
            raise ValueError(f"unknown sweep parameter(s) {sorted(unknown)}; "
                             f"known: {sorted(dict.fromkeys(p for p, _, _ in plan))}")
        plan = [row for row in plan if row[0] in parameters]
    rows, start = [], time.perf_counter()
    for i, (parameter, value, settings) in enumerate(plan):
        figures = []
        for seed in range(seeds):
            figures.append(example.run(case, "paper", seed, scenario=scenario, n_particles=n_particles,
                                       workers=workers, **settings).figures)
        row = {"parameter": parameter, "value": value}
        for key in FIGURES:
            values = np.array([np.nan if f.get(key) is None else f[key] for f in figures], float)
            row[key] = float(np.nanmean(values)) if np.isfinite(values).any() else None
        rows.append(row)
        if not quiet:
            print(f"[{i + 1}/{len(plan)}, {time.perf_counter() - start:.0f} s] {parameter} = {value}: "
                  f"RA {row['ra']:.3f}, alpha-lambda {row['alpha_lambda_pass_rate']:.3f}", file=sys.stderr)
    return rows


def table(rows: list[dict]) -> str:
    lines = [f"  {'parameter':<16} {'value':<56} {'RMSE th':>8} {'RMSE ga':>8} {'RMAD ga':>8} {'RA':>7} "
             f"{'RMAD RUL':>8} {'a-l pass':>8}"]
    for r in rows:
        cells = [100 * r[k] if r[k] is not None else np.nan for k in
                 ("rmse_theta", "rmse_gamma", "rmad_gamma", "ra", "rmad_rul", "alpha_lambda_pass_rate")]
        lines.append(f"  {r['parameter']:<16} {r['value']:<56} " + " ".join(f"{c:7.2f}%" for c in cells))
    return "\n".join(lines)


def plot(rows: list[dict], path: Path, case) -> list[Path]:
    plt = pyplot("Agg")

    groups = list(dict.fromkeys(r["parameter"] for r in rows))
    studies = [g for g in groups if g != "paper -> named"]
    fig = plt.figure(figsize=(3.6 * max(len(studies), 1), 8.5))
    grid = fig.add_gridspec(2, max(len(studies), 1), height_ratios=(1, 1.3))
    axes = [fig.add_subplot(grid[0, i]) for i in range(len(studies))]
    if "paper -> named" in groups:
        axes.append(fig.add_subplot(grid[1, :]))
        studies.append("paper -> named")
    for ax, group in zip(axes, studies):
        part = [r for r in rows if r["parameter"] == group]
        x = np.arange(len(part))
        for key, label in (("ra", "RA"), ("alpha_lambda_pass_rate", "alpha-lambda pass"),
                           ("rmse_gamma", "RMSE gamma"), ("rmad_rul", "RMAD RUL")):
            ax.plot(x, [np.nan if r[key] is None else r[key] for r in part], "o-", label=label)
        ladder_panel = group == "paper -> named"
        ax.set_xticks(x, [r["value"] for r in part], rotation=12 if ladder_panel else 30, ha="right", fontsize=7)
        ax.set_title(group if not ladder_panel else "from the paper's tuning to the named preset, one change at a time")
        ax.set_ylim(0, 1.05)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"Jha et al. (2016), section 6.4, as a sweep, case {case.name} (means over seeds)")
    return [save_figure(fig, path, dpi=100)]


def main(argv=None) -> list[dict]:
    parser = argparse.ArgumentParser(description="Tuning sweep of Jha et al. (2016), section 6.4, on the torsion bar")
    parser.add_argument("--case", choices=sorted(example.CASES), default="b-md")
    parser.add_argument("--seeds", type=int, default=3, help="noise seeds per setting (default 3)")
    parser.add_argument("--particles", type=int, help="particles (default: the case's)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, help="directory for sweep.csv, sweep.json, sweep.png")
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    args = parser.parse_args(argv)
    if args.seeds < 1:
        parser.error("--seeds must be at least 1")
    rows = sweep(args.case, args.seeds, args.particles, args.workers, args.quiet)
    print(f"Jha et al. (2016), section 6.4, sweep of case {args.case}, {args.seeds} seed(s) per setting "
          f"(RA, RMAD RUL, alpha-lambda over predictions after t = {example.CASES[args.case].after:g} s)")
    print(table(rows))
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "sweep.json").write_text(json.dumps(rows, indent=2))
        with open(args.out / "sweep.csv", "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
        write_figures(plot, rows, args.out / "sweep.png", example.CASES[args.case])
        print(f"  wrote {args.out / 'sweep.csv'}, sweep.json and sweep.png")
    return rows


if __name__ == "__main__":
    run_main(main)
