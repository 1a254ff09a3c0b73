"""Tidy tables of a fleet's results: one row per (asset, time), columns of plain numpy arrays.

Four tables, each a mapping of column name to a numpy array (all of one length):

* ``alarms``: ``asset``, ``t`` (the first alarm), ``arr`` (one row per ARR in alarm then);
* ``estimates`` (every ``report_every`` filter steps): ``asset``, ``hypothesis``, ``step``, ``t``,
  ``theta_mean``, ``theta_p5``, ``theta_p50``, ``theta_p95``, the same four of ``gamma``, ``ess``
  and ``log_evidence``;
* ``rul`` (every ``rul_every`` filter steps): ``asset``, ``step``, ``t``, ``mean``, ``p5``,
  ``p50``, ``p95`` (s; censored particles count as ``+inf`` in the quantiles), ``censored`` (the
  weight that does not fail within the horizon), ``hypothesis`` (the most probable),
  ``probability`` and ``status`` (of :func:`~prognosis.isolation.decide`);
* ``residuals`` (every asset, alarm or not, from :meth:`~prognosis.fleet.FleetMonitor.run`): ``asset``,
  ``arr``, ``t``, ``low``, ``high``, ``band_low``, ``band_high``: each ARR's ``-r_n`` in at most
  :data:`~prognosis.fleet.traces.TRACE_BUCKETS` buckets, its envelope and the threshold band
  (:func:`~prognosis.fleet.traces.residual_trace`), what a chart of the asset needs.

Asset ids are written as strings.  :meth:`FleetResult.frame` gives a pandas DataFrame (pandas is
imported on demand); ``bgphm fleet`` writes the tables to Parquet.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from bondgraph.optional import pandas_for

from ..errors import PrognosisError

__all__ = ["COLUMNS", "INTEGER", "TABLES", "TEXT", "FleetResult", "empty_table"]

TABLES = ("alarms", "estimates", "rul", "residuals")
COLUMNS = {
    "alarms": ("asset", "t", "arr"),
    "estimates": ("asset", "hypothesis", "step", "t", "theta_mean", "theta_p5", "theta_p50", "theta_p95",
                  "gamma_mean", "gamma_p5", "gamma_p50", "gamma_p95", "ess", "log_evidence"),
    "rul": ("asset", "step", "t", "mean", "p5", "p50", "p95", "censored", "hypothesis", "probability", "status"),
    "residuals": ("asset", "arr", "t", "low", "high", "band_low", "band_high"),
}
TEXT = {"asset", "arr", "hypothesis", "status"}
INTEGER = {"step"}


def empty_table(name: str) -> dict:
    """A table with its columns and no rows."""
    return {c: np.empty(0, object if c in TEXT else int if c in INTEGER else float) for c in COLUMNS[name]}


@dataclass
class FleetResult:
    """The tables of a fleet run (or of one :meth:`~prognosis.fleet.FleetMonitor.update`).

    Examples
    --------
    >>> result = FleetResult()
    >>> result.add("rul", asset=["a"], step=[0], t=[1.5], mean=[10.0], p5=[8.0], p50=[9.5], p95=[np.inf],
    ...            censored=[0.1], hypothesis=["R/linear"], probability=[1.0], status=["isolated"])
    >>> table = result.table("rul")
    >>> table["asset"].tolist(), table["p95"].tolist()
    (['a'], [inf])
    >>> len(FleetResult.concat([result, result]).table("rul")["t"])
    2
    """

    parts: dict = field(default_factory=lambda: {name: [] for name in TABLES})
    particles: dict = field(default_factory=dict)  # asset -> {hypothesis: {"theta", "gamma"}}, on request
    skipped: dict = field(default_factory=dict)  # asset -> why its record was left out (on_bad_record="skip")

    def add(self, name: str, **columns) -> None:
        """Append rows to table ``name`` (every column of the table, arrays of one length)."""
        missing = set(COLUMNS[name]) - set(columns)
        if missing:
            raise PrognosisError(f"table {name!r}: columns {sorted(missing)} missing")
        self.parts[name].append({c: _column(c, columns[c]) for c in COLUMNS[name]})

    def table(self, name: str) -> dict:
        """Table ``name`` as a mapping column -> array."""
        if name not in TABLES:
            raise PrognosisError(f"no table {name!r}; tables: {', '.join(TABLES)}")
        parts = self.parts[name]
        if not parts:
            return empty_table(name)
        if len(parts) > 1:  # join once, keep the joined table
            self.parts[name] = parts = [{c: np.concatenate([p[c] for p in parts]) for c in COLUMNS[name]}]
        return dict(parts[0])

    @property
    def alarms(self) -> dict:
        return self.table("alarms")

    @property
    def estimates(self) -> dict:
        return self.table("estimates")

    @property
    def rul(self) -> dict:
        return self.table("rul")

    @property
    def residuals(self) -> dict:
        return self.table("residuals")

    def scores(self, truth: dict, alpha: float = 0.2) -> dict:
        """The RUL predictions scored against each asset's true end of life (``truth``: asset -> ``{"eol": s}``,
        ``None`` for an asset that does not fail): per asset :func:`~prognosis.metrics.scores_against_truth`
        (without its per-prediction lists), and pooled over every prediction
        (:func:`~prognosis.metrics.pooled_scores`).  The table keeps the 5, 50 and 95 % percentiles, so the
        25-75 % band is not scored.  Assets of ``truth`` without a RUL row are listed in ``without_rul``.

        >>> result = FleetResult()
        >>> result.add("rul", asset=["a", "a"], step=[0, 1], t=[1.0, 2.0], mean=[9.0, 8.0], p5=[7.0, 6.0],
        ...            p50=[9.0, 8.0], p95=[11.0, 10.0], censored=[0.0, 0.0], hypothesis=["R/linear"] * 2,
        ...            probability=[1.0, 1.0], status=["isolated"] * 2)
        >>> scored = result.scores({"a": {"eol": 10.5}, "b": {"eol": 4.0}})
        >>> scored["pooled"]["predictions"], scored["assets"]["a"]["coverage_90"], scored["without_rul"]
        (2, 1.0, ['b'])
        """
        from prognosis.metrics import pooled_scores, scores_against_truth

        rul = self.rul
        per_asset, full, without = {}, {}, []
        for asset, entry in truth.items():
            if entry.get("eol") is None:
                continue
            rows = rul["asset"] == asset
            if not rows.any():
                without.append(asset)
                continue
            nan = np.full(int(rows.sum()), np.nan)
            percentiles = np.column_stack([rul["p5"][rows], nan, rul["p50"][rows], nan, rul["p95"][rows]])
            full[asset] = scores_against_truth(rul["t"][rows], percentiles, rul["mean"][rows], entry["eol"], alpha)
            per_asset[asset] = {k: v for k, v in full[asset].items()
                                if k not in ("true_rul", "relative_accuracy", "within_alpha", "inside_90",
                                             "coverage_50")}
        return {"pooled": pooled_scores(full), "assets": per_asset, "without_rul": sorted(without)}

    def rows(self, name: str) -> int:
        """Number of rows of table ``name``."""
        return sum(len(p["asset"]) for p in self.parts[name])

    def frame(self, name: str):
        """Table ``name`` as a pandas DataFrame."""
        pd = pandas_for("FleetResult.frame")
        return pd.DataFrame(self.table(name))

    def for_asset(self, asset: object) -> "FleetResult":
        """The rows of one asset."""
        out = FleetResult()
        for name in TABLES:
            table = self.table(name)
            mine = table["asset"] == str(asset)
            out.add(name, **{c: v[mine] for c, v in table.items()})
        return out

    @staticmethod
    def concat(results: Iterable["FleetResult"]) -> "FleetResult":
        """One result holding the rows of all."""
        out = FleetResult()
        for result in results:
            for name in TABLES:
                out.parts[name] += result.parts[name]
            out.particles.update(result.particles)
            out.skipped.update(result.skipped)
        return out


def _column(name: str, values) -> np.ndarray:
    if name in TEXT:
        return np.array([str(v) for v in values], dtype=object)
    return np.asarray(values, dtype=int if name in INTEGER else float).reshape(-1)
