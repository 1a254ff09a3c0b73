"""prognosis.fleet: many assets in one vectorized filter, with results that do not depend on batching.

* :class:`FleetMonitor` (:mod:`.monitor`): detection, isolation by evidence, estimation and RUL per
  asset, each asset starting at its own alarm;
* :class:`FleetFilter` (:mod:`.filter`): the particle arrays of every (asset, hypothesis) row and the
  vectorized SIR step on per-asset random streams (:mod:`prognosis.random_streams`);
* :mod:`.rul`: closed-form crossing times and per-asset RUL summaries;
* :class:`FleetResult` (:mod:`.results`): the tidy tables (alarms, estimates, RUL, residual traces);
* :func:`~.traces.residual_trace` (:mod:`.traces`): what a fleet keeps of each residual, a short envelope;
* :func:`write_checkpoint`, :func:`read_checkpoint` (:mod:`.checkpoint`): a stream's state on disk as
  sealed numeric arrays, never a pickle.
"""

from .checkpoint import read_checkpoint, write_checkpoint
from .filter import FleetFilter
from .fleet_monitor import FLEET_LAWS, FleetMonitor
from .results import FleetResult

__all__ = ["FLEET_LAWS", "FleetFilter", "FleetMonitor", "FleetResult", "read_checkpoint", "write_checkpoint"]
