"""One asset of a streaming fleet: its ARRs' online evaluation and where it stands.

A :class:`LiveAsset` takes the asset's micro-batches, evaluates every ARR online with bounded memory
(:class:`diagnosis.StreamingEvaluation`: a ring buffer of the derivative window and running
integrals), aligns the ARRs' final samples (those whose centred derivative is known), watches for the
first alarm and then queues the samples due for a filter step (every ``stride`` samples from the
alarm).  It keeps the last ``persistence`` final samples for the start of the filter at the alarm,
and nothing else of the past: its memory does not grow with the stream.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from diagnosis import StreamingEvaluation

__all__ = ["Final", "LiveAsset"]


@dataclass
class Final:
    """Aligned final samples of every ARR: ``t`` (n,), ``y = -r_n`` (n, M), alarms (n, M), points per ARR (n, P_m)."""

    t: np.ndarray
    y: np.ndarray
    alarm: np.ndarray
    points: list

    def __len__(self) -> int:
        return self.t.size

    def take(self, index) -> "Final":
        return Final(self.t[index], self.y[index], self.alarm[index], [p[index] for p in self.points])

    @staticmethod
    def join(parts: Sequence["Final"]) -> "Final":
        return Final(np.concatenate([p.t for p in parts]), np.concatenate([p.y for p in parts]),
                     np.concatenate([p.alarm for p in parts]),
                     [np.concatenate([p.points[m] for p in parts]) for m in range(len(parts[0].points))])


@dataclass
class LiveAsset:
    """The streaming state of one asset (see the module docstring)."""

    asset: object
    evaluators: list
    persistence: int
    pending: list = field(default_factory=list)  # per ARR: final samples not yet final for every ARR
    count: int = 0  # aligned final samples so far
    recent: Final | None = None  # the last `persistence` of them
    alarm: int | None = None  # sample index of the first alarm
    stride: int | None = None
    sample_step: float | None = None
    hypotheses: list = field(default_factory=list)  # started at the alarm
    starts: list = field(default_factory=list)
    rows: np.ndarray | None = None  # the filter's rows of this asset
    queue: list = field(default_factory=list)  # (t, y (M,), points per ARR (P_m,)) due for a filter step

    @classmethod
    def start(cls, asset, arrs: Sequence, options: Sequence[Mapping]) -> "LiveAsset":
        evaluators = [StreamingEvaluation(a, **o) for a, o in zip(arrs, options)]
        return cls(asset, evaluators, max(int(o.get("persistence", 1)) for o in options),
                   pending=[None] * len(evaluators))

    def check(self, t: np.ndarray, signals: Mapping) -> list:
        """Raise what :meth:`push` would raise for this micro-batch, for any ARR, before any evaluation moves;
        the batch as each ARR's stream read it (for :meth:`push`, which then does not read it again)."""
        return [evaluator.check(t, signals) for evaluator in self.evaluators]

    def push(self, t: np.ndarray, signals: Mapping, checked: list | None = None) -> Final | None:
        """Feed a micro-batch (``checked``: what :meth:`check` returned for it); the samples that became final for
        every ARR (None if none did)."""
        # the alarm's band alone until the first alarm; after it only the residuals matter: no thresholds
        bands = "alarm" if self.alarm is None else "none"
        for m, evaluator in enumerate(self.evaluators):
            chunk = evaluator.push(t if checked is None else checked[m], signals, thresholds=bands)
            if len(chunk.t):
                part = Final(chunk.t, -chunk.residual[:, None], chunk.alarm[:, None],
                             [np.stack(chunk.points, axis=1) if chunk.points else np.empty((len(chunk.t), 0))])
                self.pending[m] = part if self.pending[m] is None else Final.join([self.pending[m], part])
        ready = min((0 if p is None else len(p)) for p in self.pending)
        if not ready:
            return None
        parts = [p.take(slice(0, ready)) for p in self.pending]
        self.pending = [p.take(slice(ready, None)) for p in self.pending]
        return Final(parts[0].t, np.concatenate([p.y for p in parts], axis=1),
                     np.concatenate([p.alarm for p in parts], axis=1), [p.points[0] for p in parts])

    def window(self, final: Final, index: int) -> Final:
        """The last ``persistence`` aligned samples up to ``final``'s sample ``index`` (those of an alarm)."""
        joined = final.take(slice(0, index + 1)) if self.recent is None else \
            Final.join([self.recent, final.take(slice(0, index + 1))])
        return joined.take(slice(-self.persistence, None))

    def remember(self, final: Final) -> None:
        """Keep the last ``persistence`` aligned samples (and the sampling step) after ``final``."""
        joined = final if self.recent is None else Final.join([self.recent, final])
        if self.sample_step is None and len(joined) >= 2:
            self.sample_step = float(joined.t[1] - joined.t[0])
        self.recent = joined.take(slice(-max(self.persistence, 2), None))
        self.count += len(final)

    def state(self) -> dict:
        """Everything needed to go on after a restart, as plain data (not the filter's rows)."""
        return {"asset": self.asset, "evaluators": [e.state() for e in self.evaluators],
                "persistence": self.persistence, "pending": [_plain(p) for p in self.pending], "count": self.count,
                "recent": _plain(self.recent), "alarm": self.alarm, "stride": self.stride,
                "sample_step": self.sample_step,
                "hypotheses": list(self.hypotheses), "starts": [tuple(map(float, s)) for s in self.starts]}

    @classmethod
    def restore(cls, state: Mapping, arrs: Sequence, options: Sequence[Mapping]) -> "LiveAsset":
        evaluators = [StreamingEvaluation.restore(a, s, **o) for a, s, o in zip(arrs, state["evaluators"], options)]
        return cls(state["asset"], evaluators, int(state["persistence"]),
                   pending=[_final(p) for p in state["pending"]], count=int(state["count"]),
                   recent=_final(state["recent"]), alarm=state["alarm"], stride=state["stride"],
                   sample_step=state["sample_step"],
                   hypotheses=list(state["hypotheses"]), starts=[tuple(s) for s in state["starts"]])


def _plain(final: Final | None) -> dict | None:
    if final is None:
        return None
    return {"t": final.t, "y": final.y, "alarm": final.alarm, "points": list(final.points)}


def _final(plain: Mapping | None) -> Final | None:
    if plain is None:
        return None
    return Final(np.asarray(plain["t"]), np.asarray(plain["y"]), np.asarray(plain["alarm"]),
                 [np.asarray(p) for p in plain["points"]])
