"""One prognosis scenario, run as a user would: a model file, a CSV, ``bgphm prognose --fail ...``.

The truth (the parameter's law, hence the end of life) comes from the scenario, the answer from the
command's ``prognosis.json``; :func:`score` compares them: whether the degrading parameter was named
(or honestly called undecided or indistinguishable), the share of the second half of life where the
median RUL is within 20 % of the truth, and how often the 5-95 % and 25-75 % bands hold the truth.
"""

from __future__ import annotations

import contextlib
import io
import json
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bgphm.cli import main as bgphm
from bgphm.files import csv_text
from bondgraph import to_json
from bondgraph.library import torsion_bar_monitorable

from . import torsion
from .laws import LAWS

ONSET, EOL = 10.0, 100.0        # s: wear from the onset to the failure value at the end of life
T_END, DT = 100.0, 0.01         # s: the record, sampled at 100 Hz
CALIBRATE = 8.0                 # s of healthy record before the onset
WITHIN = 0.2                    # the median RUL is "within" when off by at most this share of the truth
#: Failure values the user gives: the paper's for b_Md (Jha et al. (2016), 6.3), ten times nominal for the
#: other frictions (what an engineer would call worn out).
FAILURES = {"b_Md": 0.45, "b_Ld": 10 * torsion.NOMINAL["b_Ld"], "f_m": 10 * torsion.NOMINAL["f_m"]}


@dataclass(frozen=True)
class Scenario:
    """A parameter wearing by a law, residual noise ("clean": speeds only; "noisy": torque as well)."""

    parameter: str
    law: str
    noise: str

    @property
    def name(self) -> str:
        return f"torsion_bar/{self.parameter}/{self.law}/{self.noise}"


def scenarios() -> list[Scenario]:
    """The torsion bar's b_Md under every law, with a clean and a noisy residual."""
    return [Scenario("b_Md", law, noise) for law in LAWS for noise in ("clean", "noisy")]


def record(scenario: Scenario, seed: int) -> dict:
    nominal = torsion.NOMINAL[scenario.parameter]
    law = LAWS[scenario.law](nominal, FAILURES[scenario.parameter], ONSET, EOL)
    noise = dict(torsion.NOISE) if scenario.noise == "noisy" else {k: v for k, v in torsion.NOISE.items()
                                                                   if k != "tau_m"}
    return torsion.simulate({scenario.parameter: law}, t_end=T_END, dt=DT, noise=noise, seed=seed)


def run(scenario: Scenario, seed: int, *, particles: int = 300, rul_every: int = 10, method: str = "sir",
        degradation: str | None = None) -> dict:
    """``prognosis.json`` of ``bgphm prognose`` on the scenario's record (exit code under ``"exit"``)."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "model.json").write_text(to_json(torsion_bar_monitorable()))
        (folder / "data.csv").write_text(csv_text(record(scenario, seed)))
        fails = [f"--fail={p}={v:g}" for p, v in FAILURES.items()]
        argv = ["--quiet", "prognose", str(folder / "model.json"), str(folder / "data.csv"), *fails,
                "--calibrate", f"{CALIBRATE:g}", "--particles", str(particles), "--rul-every", str(rul_every),
                "--seed", str(seed), "--filter", method, "--out", str(folder / "out"),
                *(["--degradation", degradation] if degradation else [])]
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()) as err:
            code = bgphm(argv)
        if code != 0:
            return {"exit": code, "error": err.getvalue().strip()}
        return {"exit": 0, **json.loads((folder / "out" / "prognosis.json").read_text())}


def score(scenario: Scenario, answer: dict) -> dict:
    """The scenario's figures from one answer: found, status, within 20 %, both coverages, RA."""
    if answer.get("exit") != 0:
        return {"found": False, "status": f"exit {answer.get('exit')}", "predictions": 0}
    named = answer.get("candidate")
    # an honest "indistinguishable" names a group; a decided answer names the parameter
    group = set(named) if isinstance(named, list) else {named} | set(answer.get("same_signature") or [])
    found = named is not None and scenario.parameter in group
    given = [p for p in answer.get("predictions", []) if ONSET < p["t"] < EOL]
    # a withheld prediction ("undecided: no law fits") is honest but gives no figure: counted apart
    predictions = [p for p in given if not p.get("withheld")]
    truth = np.array([EOL - p["t"] for p in predictions])
    figures = {"found": bool(found), "candidate": named, "status": answer.get("status"),
               "degradation": answer.get("degradation"), "detection_time": answer.get("detection_time"),
               "predictions": len(predictions), "withheld": len(given) - len(predictions)}
    if not predictions:
        return figures
    median = np.array([_number(p["rul_median"]) for p in predictions])
    p5, p95 = (np.array([_number(p[k]) for p in predictions]) for k in ("rul_p5", "rul_p95"))
    second = np.array([p["t"] >= (ONSET + EOL) / 2 for p in predictions])
    within = np.abs(median - truth) <= WITHIN * truth
    figures.update({
        "within_20pct_second_half": float(np.mean(within[second])) if second.any() else None,
        "coverage_90": float(np.mean((p5 <= truth) & (truth <= p95))),
        "ra": float(np.mean(1 - np.abs(truth - np.array([_number(p["rul_mean"]) for p in predictions])) / truth)),
    })
    if all("rul_p25" in p for p in predictions):
        p25, p75 = (np.array([_number(p[k]) for p in predictions]) for k in ("rul_p25", "rul_p75"))
        figures["coverage_50"] = float(np.mean((p25 <= truth) & (truth <= p75)))
        figures["pit"] = pit_histogram(predictions, truth)
    return figures


PIT_EDGES = (0.05, 0.25, 0.5, 0.75, 0.95)  # the predicted quantiles: six bins of the PIT between them
QUARTERS = 4


def pit_histogram(predictions: list[dict], truth: np.ndarray) -> list[list[int]]:
    """Counts of the truth's place among the predicted quantiles, per quarter of the life after onset.

    Row q: predictions made in the q-th quarter of (ONSET, EOL); column b: the truth below the 5 %
    quantile (b = 0), between the 5 and 25 % ones (1), ..., above the 95 % one (5).  A calibrated
    band fills the bins as 5, 20, 25, 25, 20, 5 % in every quarter.
    """
    keys = ("rul_p5", "rul_p25", "rul_median", "rul_p75", "rul_p95")
    counts = np.zeros((QUARTERS, len(PIT_EDGES) + 1), int)
    for p, true in zip(predictions, truth):
        quarter = min(QUARTERS - 1, int((p["t"] - ONSET) / (EOL - ONSET) * QUARTERS))
        counts[quarter, int(np.searchsorted([_number(p[k]) for k in keys], true))] += 1
    return counts.tolist()


def _number(value) -> float:
    return float("inf") if value is None else float(value)
