"""Small fleets for the fleet tests: noisy RLC circuits whose resistance drifts up (or not), as CSV files."""

from __future__ import annotations

import builtins
from pathlib import Path

import numpy as np

from bgphm.files import csv_text
from bondgraph import simulate
from bondgraph.library import rlc_circuit
from diagnosis import add_noise, as_record

#: Drift onsets (s) of R (10 ohm, drifting at 4 ohm/s, failing at 20 ohm); None stays healthy.
ONSETS = {"c0": 0.3, "c1": None, "c2": 0.6, "c3": 0.5, "c4": None, "c5": 0.7}
T_END = 2.0  # s, at 1 kHz
NOISE = {"i": 1e-4, "v_C": 1e-3}


def rlc_record(onset: float | None, seed: int, t_end: float = T_END):
    """A noisy record of the RLC circuit, R drifting from ``onset`` (V, i, v_C at 1 kHz)."""
    t = np.linspace(0.0, t_end, int(t_end * 1000) + 1)
    drift = (lambda t: 10.0 + 4.0 * max(0.0, t - onset)) if onset is not None else None
    run = simulate(rlc_circuit(), (0.0, t_end), {"V": lambda t: 5 + np.sin(7 * t)}, t_eval=t,
                   parameters={"R": drift} if drift else {})
    return add_noise(as_record(run.record()), NOISE, seed=seed)


def write_fleet(folder: Path, onsets: dict = ONSETS) -> Path:
    """One CSV per asset in ``folder`` (created); returns it."""
    folder.mkdir(parents=True, exist_ok=True)
    for seed, (asset, onset) in enumerate(onsets.items()):
        record = rlc_record(onset, seed)
        (folder / f"{asset}.csv").write_text(csv_text({"t": record.t, **record.columns}))
    return folder


def spec(**settings):
    """A cheap job on these records: both ARRs of the RLC circuit, R failing at 20 ohm, a linear law."""
    from bgphm.fleet import FleetSpec

    options = {"noise_std": {"ARR_J1": 2.8e-3, "ARR_J0": 2.6e-4}, "laws": ["linear"], "dt": 0.05, "n_particles": 100,
               "rul_every": 4, "detection": {"ARR_J1": {"margin": 0.011}, "ARR_J0": {"margin": 1.1e-3}},
               "healthy_until": 0.2, **settings}
    return FleetSpec("rlc", {"R": 20.0}, **options)


def without_dask(monkeypatch) -> None:
    """Make ``import dask`` and ``import distributed`` fail for the rest of the test (a machine without the extra)."""
    real_import = builtins.__import__

    def without_distributed(name, *args, **kwargs):
        if name.split(".")[0] in ("dask", "distributed"):
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", without_distributed)
