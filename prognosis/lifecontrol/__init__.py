"""Energy-driven deterioration, distribution-free bounds, Monte Carlo RUL and RUL control.

Following Rodriguez Obando et al. (2021):

* :mod:`.deterioration`: the energy an element of the bond graph dissipates, appended to its state
  equations as a deterioration ``D`` that drives a degrading coefficient;
* :mod:`.chebyshev`: Chebyshev bounds on a Gaussian-free estimate, and an initial covariance from bounds;
* :mod:`.montecarlo`: the RUL from draws of the estimate propagated to failure;
* :mod:`.rulcontrol`: the operating point that keeps ``Pr(EoL <= t_ref)`` under a level.

Examples
--------
>>> import numpy as np
>>> rul = monte_carlo_rul(lambda x, t: np.vstack([-x[1], 0 * x[1]]), [1.0, 0.1], np.diag([0.0, 1e-4]),
...                       lambda x: x[0] - 0.5, horizon=20.0, dt=0.1, n_samples=500, seed=1)
>>> bool(4.5 < float(rul.median) < 5.5)
True
"""

from .chebyshev import chebyshev_bounds, chebyshev_intervals, chebyshev_level, chebyshev_scale, covariance_from_bounds
from .deterioration import DeteriorationEquations, energy_deterioration
from .montecarlo import monte_carlo_rul, sample_gaussian
from .rulcontrol import RULControlWarning, RULController, RULDecision

__all__ = [
    "DeteriorationEquations", "RULControlWarning", "RULController", "RULDecision", "chebyshev_bounds",
    "chebyshev_intervals", "chebyshev_level", "chebyshev_scale", "covariance_from_bounds", "energy_deterioration",
    "monte_carlo_rul", "sample_gaussian",
]
