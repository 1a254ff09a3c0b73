"""Parameters from healthy records, through the ARRs: what the records identify, the estimates, their intervals.

On a healthy machine every ARR's nominal residual ``r_n(signals; theta)`` is zero but for noise, when
``theta`` holds the machine's true parameters.  :func:`estimate_parameters` therefore finds the parameters
that make the residuals of every ARR, over every record, smallest.  Each ARR is written as a sum of terms,
``coefficient(theta) * feature(signals)``, and each feature is integrated over windows of
:data:`INTEGRATION_WINDOW` samples: a derivative term ``c dx/dt`` becomes ``c (x(b) - x(a))``, exact and without
the derivative filter's noise, and every other term is averaged (windows that reach across an input's step are
left out).  The fit makes smallest the sum of the window residuals squared, each divided by the noise that the
sensors give it at the parameters tried: the signals' white noise (estimated from their fourth differences)
reaches every feature, through its slope where the feature is a curve of the signals, and the residual through
the coefficients, ``sqrt(c(theta)' N c(theta))``.  That is the maximum-likelihood fit of noisy regressors
(errors in variables): unbiased where plain least squares would shrink the coefficients of noisy features
towards zero, and blind to scaling an ARR as a whole (a fit cannot make an ARR quieter by making its
parameters smaller).  A curved feature's mean shift by the noise (``omega**2`` gains ``sigma**2``) is taken
off its samples, and a prior about the datasheet values (:data:`PRIOR`, 50 %) keeps the directions the
records barely see near them.  Most ARRs are linear in their parameters; the others (a valve's ``sqrt``, a
belt's ``1/k``) are fitted the same way, with the exact Jacobian.

Identifiability comes first (:func:`identifiability`): the Jacobian of the residuals with respect to the
relative change of each parameter, over the records, says which parameters these ARRs and these records can
tell apart.  A direction of parameters that leaves the residuals (almost) unchanged cannot be estimated, and
neither can one the records tell less well than the datasheet (a relative standard deviation above the
prior's): a fit along it would follow the residuals' smallest flaws, a torsion bar's stiffness 40 times its
value on a record that barely twists the shaft.  Either way its parameters are reported together, with the
combination the data do fix (the coefficient of the term of the ARR two of them share, e.g.
``J_m + J_Md/k_belt**2``, or the products of powers a scaling of the group leaves unchanged, e.g.
``b/J, k_m/J``), and the fit keeps one of them at its datasheet value so that the others carry the
combination.

The intervals are ``level`` (95 %) confidence intervals of the linearized fit: a sandwich covariance (the
objective's Hessian about the scores) whose middle adds the ARRs' scores window by window (ARRs that share a
sensor share its noise) with Newey-West lags, scaled for the degrees of freedom the windows leave, with a t
quantile.  :func:`uncertainty_boxes` turns them, or the spread between records, into the multiplicative
``uncertainty=(lo, hi)`` boxes the thresholds use.

Example
-------
A DC motor whose datasheet friction is 40 % low and inertia 30 % high, told by a healthy bench run:

>>> import numpy as np
>>> from bondgraph import simulate
>>> from bondgraph.library import dc_motor
>>> from diagnosis import add_noise, as_record
>>> t = np.linspace(0.0, 2.0, 2001)
>>> U = lambda t: 12.0 * (t >= 0.05) - 6.0 * (t >= 1.0)
>>> true = dc_motor(b=1.4e-4, J=0.77e-4)
>>> record = add_noise(as_record(simulate(true, (0, 2), {"U": U}, t_eval=t).record()), {"i": 0.01, "omega": 0.2},
...                    seed=1)
>>> fit = estimate_parameters(dc_motor(b=1e-4, J=1e-4), [record], parameters=["b", "J"])
>>> {p: round(fit.values[p] / v, 2) for p, v in {"b": 1.4e-4, "J": 0.77e-4}.items()}
{'b': 1.0, 'J': 1.0}
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np
import sympy as sp
from scipy import optimize, stats

from bondgraph.errors import SettingError

from ._fit_covariance import fit_covariance
from ._revalued import revalued
from ._windowed_residuals import INTEGRATION_WINDOW, QUADRATURES, Problem, windowed_problem
from .derivation import derive_arrs
from .records import as_record
from .set_membership import set_membership_boxes

__all__ = ["INTEGRATION_WINDOW", "PRIOR", "QUADRATURES", "Identifiability", "ParameterEstimate", "estimate_parameters",
           "identifiability", "uncertainty_boxes"]

#: A direction of relative parameter changes whose singular value is below this share of the largest is not
#: identified by the records (it would need a relative precision beyond what double precision and filtered
#: derivatives give).
SINGULAR_FLOOR = 1e-7
#: The datasheet's relative standard deviation that :func:`estimate_parameters` assumes by default: a datasheet
#: value within a factor of about two of the machine's.
PRIOR = 0.5


@dataclass(frozen=True)
class Identifiability:
    """Which parameters a set of records identifies through the ARRs.

    Attributes
    ----------
    identified : list of str
        Parameters the fit can estimate one by one.
    combinations : list of dict
        Groups of parameters the records see only together: ``parameters`` (the group), ``expression`` (the
        combination the data fix, as text: the ARR's term two members share, or the products of powers the
        group's scaling leaves unchanged), ``kept`` (the parameter the fit keeps at its datasheet value so that
        the others carry the combination), ``direction`` (member -> its relative change along the change the
        records cannot see, per relative change of the kept member) and ``weak`` (the records see the
        direction, less well than the datasheet tells it, rather than not at all).
    unseen : list of str
        Parameters in no ARR (the records cannot say anything of them).
    singular_values : list of float
        Of the Jacobian in relative changes, largest first (their spread is its conditioning).
    """

    identified: list
    combinations: list
    unseen: list
    singular_values: list

    @property
    def condition(self) -> float:
        s = [v for v in self.singular_values if v > 0]
        return s[0] / s[-1] if s else math.inf


@dataclass
class ParameterEstimate:
    """What :func:`estimate_parameters` found.

    Attributes
    ----------
    values : dict
        Every parameter of the model: its estimate where it was estimated, else its datasheet value.
    datasheet : dict
        The values the model came with.
    intervals : dict
        Estimated parameter -> its ``level`` confidence interval (lo, hi).
    std : dict
        Estimated parameter -> its standard error.
    identifiability : Identifiability
    given_held : dict
        Estimated parameter -> its interval were the weakly seen parameters (held at their datasheet values)
        exactly there: what the thresholds' boxes take, the held parameters keeping boxes of their own.
    residual_std : dict
        ARR -> the robust spread of its residual at the fit; ``correlation`` ARR -> its integrated
        autocorrelation time in samples (the intervals' inflation).
    samples : int
        Residual samples the fit used (all ARRs, all records).
    level : float
    """

    values: dict
    datasheet: dict
    intervals: dict = field(default_factory=dict)
    std: dict = field(default_factory=dict)
    given_held: dict = field(default_factory=dict)
    identifiability: Identifiability | None = None
    residual_std: dict = field(default_factory=dict)
    correlation: dict = field(default_factory=dict)
    samples: int = 0
    level: float = 0.95

    @property
    def estimated(self) -> list:
        return list(self.intervals)

    def model(self, bg, boxes: Mapping | None = None):
        """A copy of ``bg`` with the estimated values (and, with ``boxes``, those uncertainty boxes)."""
        return revalued(bg, {p: self.values[p] for p in self.intervals}, boxes)

    def as_dict(self) -> dict:
        ident = self.identifiability
        return {"level": self.level, "samples": self.samples,
                "parameters": {p: {"datasheet": self.datasheet[p], "estimate": self.values[p],
                                   "interval": list(self.intervals[p]), "std": self.std[p],
                                   "interval_given_held": list(self.given_held.get(p, self.intervals[p])),
                                   "change": self.values[p] / self.datasheet[p] - 1.0 if self.datasheet[p] else None}
                               for p in self.intervals},
                "combinations": [] if ident is None else ident.combinations,
                "unseen": [] if ident is None else ident.unseen,
                "condition": None if ident is None or not math.isfinite(ident.condition) else ident.condition,
                "residual_std": dict(self.residual_std), "correlation": dict(self.correlation)}


def _choose(bg, arrs: Sequence, parameters: Sequence[str] | None) -> tuple[list, list]:
    """The parameters to fit (those asked, else every parameter of an ARR) and those in no ARR."""
    in_arrs = list(dict.fromkeys(p for arr in arrs for p in sorted(arr.parameters)))
    values = bg.parameters
    if parameters is None:
        chosen = [p for p in values if p in in_arrs]
    else:
        unknown = [p for p in parameters if p not in values]
        if unknown:
            raise SettingError("parameters", f"{{setting}}: the model has no parameter {unknown[0]!r} (parameters: "
                               f"{', '.join(values)})")
        chosen = list(dict.fromkeys(parameters))
    unseen = [p for p in chosen if p not in in_arrs]
    return [p for p in chosen if p in in_arrs and values[p] != 0], unseen


def _rank_out(problem: Problem, x: np.ndarray, prior: float | None = None) -> tuple[list, list, np.ndarray]:
    """Split the parameters into those the Jacobian at ``x`` identifies and groups it does not: one direction
    at a time, its largest member kept out (at its datasheet value).  A direction is not identified where the
    Jacobian is singular to working precision (:data:`SINGULAR_FLOOR`), or, with ``prior``, where the records
    would tell its relative change with a standard deviation above the datasheet's own (the residuals being
    scaled to unit noise, ``1 / singular value``): a fit would then follow the residuals' smallest flaws along
    it, as far as the prior lets it.  Each group comes with its direction (member -> its relative change per
    relative change of the kept member) and whether it is only weakly seen."""
    names = list(problem.names)
    active = list(range(len(names)))
    groups = []
    jac = problem.jacobian(x)
    scale = np.linalg.norm(jac, axis=0)
    scale[scale == 0] = 1.0
    singular = np.linalg.svd(jac / scale, compute_uv=False)
    while active:
        sub = jac[:, active]
        if len(active) > 1 or not np.any(sub):
            _, s, vt = np.linalg.svd(sub / scale[active], full_matrices=False)
            if not (s[-1] > SINGULAR_FLOOR * s[0] and s[-1] > 0):
                groups.append(_group(names, active, vt[-1] / scale[active], jac, weak=False))
                continue
        if prior is None:
            break
        _, s, vt = np.linalg.svd(sub, full_matrices=False)
        if s[-1] * prior >= 1.0:
            break
        groups.append(_group(names, active, vt[-1], jac, weak=True))
    return [names[k] for k in active], groups, singular


def _group(names: list, active: list, direction: np.ndarray, jac: np.ndarray, weak: bool) -> tuple:
    """The members of a direction (its components above a tenth of the largest), the one kept out of
    ``active``, the direction per member relative to the kept one, and whether it is weakly seen.

    The member kept (at its datasheet value) is the one that leaves the others best told apart: the largest
    smallest singular value of the unit-noise Jacobian without it.  A pump's gear ratio rather than its
    friction: held, the gear leaves each of the motor constant, the inertia and the friction fixed by one
    combination of its own; the friction, poorly seen, would pass its spread on to the gear and the motor
    constant, and their boxes would blunt every threshold they enter."""
    largest = np.abs(direction).max()
    members = [active[k] for k in np.flatnonzero(np.abs(direction) > 0.1 * largest)]

    def left(k: int) -> float:
        rest = [j for j in active if j != k]
        return float(np.linalg.svd(jac[:, rest], compute_uv=False)[-1]) if rest else math.inf

    kept = max(members, key=lambda k: (left(k), abs(direction[active.index(k)])))
    along = {names[k]: float(direction[active.index(k)] / direction[active.index(kept)]) for k in members}
    active.remove(kept)
    return [names[k] for k in members], names[kept], along, weak


def _weakly_seen(members: list) -> str:
    """The label of a direction the records tell less well than the datasheet."""
    what = members[0] if len(members) == 1 else " and ".join([", ".join(members[:-1]), members[-1]]) + " together"
    return f"{what}: the records tell less than the datasheet"


def _combination(arrs: Sequence, members: list, kept: str, direction: Mapping) -> str:
    """What the data fix of a group.  Two members: the coefficient, in an ARR holding both, of the term that
    joins them (``J_m + J_Md/k_belt**2``).  More: the products of powers that the group's direction leaves
    unchanged, one per member besides the kept one (``C_1*R_1, R_2/R_1``), when the direction's ratios are
    simple fractions; else their ratios."""
    symbols = {sp.Symbol(m) for m in members}
    if len(members) == 1:
        return f"{members[0]} alone: too weakly seen to estimate"
    if len(members) == 2:
        for arr in arrs:
            if not symbols & arr.nominal.free_symbols:
                continue
            expression = sp.expand(arr.nominal)
            signal_atoms = [a for a in expression.atoms(sp.Derivative, sp.Integral, sp.core.function.AppliedUndef)
                            if not a.free_symbols & symbols]
            collected = sp.collect(expression, signal_atoms, evaluate=False) if signal_atoms else {}
            for coefficient in collected.values():
                if len(coefficient.free_symbols & symbols) >= 2:
                    return str(sp.simplify(coefficient))
    exponents = {m: Fraction(direction[m]).limit_denominator(4) for m in members}
    if any(abs(float(exponents[m]) - direction[m]) > 1e-3 for m in members):
        return "the ratios of " + ", ".join(members)
    invariants = [sp.Symbol(m) * sp.Symbol(kept) ** sp.Rational(-exponents[m].numerator, exponents[m].denominator)
                  for m in members if m != kept]
    return ", ".join(str(v) for v in invariants)


def identifiability(bg, records: Sequence, parameters: Sequence[str] | None = None, *, arrs: Sequence | None = None,
                    window: int | None = None, quadrature: str = "trapezoid",
                    prior: float | None = PRIOR) -> Identifiability:
    """Which parameters these records identify through the ARRs, at the model's (datasheet) values.

    >>> import numpy as np
    >>> from bondgraph import simulate
    >>> from bondgraph.library import dc_motor
    >>> t = np.linspace(0.0, 1.0, 1001)
    >>> step = simulate(dc_motor(), (0, 1), {"U": lambda t: 12.0 * (t > 0.05)}, t_eval=t).record()
    >>> seen = identifiability(dc_motor(), [step])
    >>> seen.identified, seen.combinations[0]["expression"]  # the current's 1 ms transient hides in the step
    (['R_a', 'k_m', 'J', 'b'], 'L_a alone: too weakly seen to estimate')
    >>> varying = simulate(dc_motor(), (0, 1), {"U": lambda t: 12.0 + 6.0 * np.sin(40.0 * t)}, t_eval=t).record()
    >>> identifiability(dc_motor(), [varying]).identified
    ['R_a', 'L_a', 'k_m', 'J', 'b']
    """
    arrs = list(arrs) if arrs is not None else derive_arrs(bg)
    return _identified(bg, arrs, [as_record(r) for r in records], parameters, window, quadrature, prior)[0]


def _identified(bg, arrs: list, records: list, parameters: Sequence[str] | None, window: int | None,
                quadrature: str, prior: float | None) -> tuple[Identifiability, Problem | None]:
    """:func:`identifiability`, and the windowed problem of every parameter chosen (None without one): the
    fit's own when the records identify each of them."""
    names, unseen = _choose(bg, arrs, parameters)
    if not names:
        return Identifiability([], [], unseen, []), None
    if prior is not None and not (math.isfinite(prior) and prior > 0):
        raise SettingError("prior", f"{{setting}} must be a relative standard deviation > 0, or None, got {prior!r}")
    if quadrature not in QUADRATURES:
        raise SettingError("quadrature", f"{{setting}} must be one of {', '.join(QUADRATURES)}, got {quadrature!r}")
    if window is not None and not (isinstance(window, int) and window >= 2):
        raise SettingError("window", f"{{setting}} must be a whole number of samples >= 2, got {window!r}")
    problem = windowed_problem(arrs, records, names, bg.parameters, window, bg.domains, quadrature)
    if not problem.blocks:
        width = int(window or INTEGRATION_WINDOW)
        raise SettingError("records", f"{{setting}}: no window of {width + 1} usable samples in any record (the "
                           "records are too short, or every stretch holds a gap or an input's step)")
    identified, groups, singular = _rank_out(problem, np.ones(len(names)), prior)
    combinations = [{"parameters": members, "kept": kept, "direction": along, "weak": weak,
                     "expression": _weakly_seen(members) if weak else _combination(arrs, members, kept, along)}
                    for members, kept, along, weak in groups]
    return Identifiability(identified, combinations, unseen, singular.tolist()), problem


# ------------------------------------------------------------------------------------------- estimation

def estimate_parameters(bg, records: Sequence, parameters: Sequence[str] | None = None, *,
                        arrs: Sequence | None = None, window: int | None = None, quadrature: str = "trapezoid",
                        level: float = 0.95, prior: float | None = PRIOR) -> ParameterEstimate:
    """Estimate a model's parameters from healthy records by making its ARRs' residuals smallest.

    Parameters
    ----------
    bg : BondGraph
        The model with its datasheet values (the starting point, and the value of every parameter not fitted).
    records : sequence of Record or mapping
        Healthy records (each with ``t`` and the ARRs' signals), from different days or operating points.
    parameters : sequence of str, optional
        The parameters to estimate; default: every parameter in an ARR that the records identify (the others
        stay at their datasheet values and are reported, see :class:`Identifiability`).
    arrs : sequence of ARR, optional
        Default: :func:`~diagnosis.derive_arrs` of ``bg`` (differentiated forms, no integral of a signal).
    window : int, optional
        Samples each row integrates the ARRs over (default :data:`INTEGRATION_WINDOW`, 50); a short record
        (a few hundred samples) needs shorter windows to leave enough rows.
    quadrature : {"trapezoid", "euler"}
        How a feature's samples are integrated over a window: the trapezoid rule (default, for records of a
        continuous machine), or the left rectangle rule, exact for records of a discrete-time model stepped by
        explicit Euler (``x[k+1] = x[k] + dt f(x[k])``, as some papers define their plants).
    level : float
        Confidence level of the intervals.
    prior : float or None
        The datasheet's own uncertainty: each parameter's relative standard deviation about its datasheet
        value (default :data:`PRIOR`, 50 %).  A direction the records barely see stays near the datasheet
        rather than swinging to absorb the residuals' estimation errors (a regularized, maximum a posteriori
        fit); a direction they see well is the data's.  None: the records alone.

    Returns
    -------
    ParameterEstimate

    Raises
    ------
    SettingError
        A parameter the model lacks, a level outside (0, 1), a bad window or quadrature, or no sample to fit on.
    """
    if not 0.0 < level < 1.0:
        raise SettingError("level", f"{{setting}} must lie in (0, 1), got {level!r}")
    arrs = list(arrs) if arrs is not None else derive_arrs(bg)
    records = [as_record(r) for r in records]
    datasheet = dict(bg.parameters)
    ident, problem = _identified(bg, arrs, records, parameters, window, quadrature, prior)
    names = ident.identified
    if not names:
        return ParameterEstimate(dict(datasheet), datasheet, identifiability=ident, level=level)
    values = dict(datasheet)
    problem, x, covariance, noise, correlation, ident = _settled(bg, arrs, records, ident, window, quadrature, prior,
                                                                 problem)
    names = ident.identified
    conditional = covariance
    kept = [g["kept"] for g in ident.combinations if g.get("weak")]
    if kept and prior is not None:
        covariance = covariance + _kept_uncertainty(arrs, records, names, kept, values, x, window, bg.domains,
                                                    quadrature, prior)
    # few windows: the residuals' spread is itself estimated, with as many degrees of freedom as windows left
    # over by the parameters (a t quantile); the ARRs over one window share its noise: the windows count, not
    # the rows
    rows = len({key for b in problem.blocks for key in b.keys})
    freedom = max(rows - len(names), 1)
    z = stats.t.ppf(0.5 + level / 2, freedom)
    theta = problem.nominal * x
    std = np.sqrt(np.maximum(np.diag(covariance), 0.0)) * np.abs(problem.nominal)
    given = np.sqrt(np.maximum(np.diag(conditional), 0.0)) * np.abs(problem.nominal)
    values.update(dict(zip(names, theta.tolist())))
    return ParameterEstimate(
        values=values, datasheet=datasheet,
        intervals={n: (float(v - z * s), float(v + z * s)) for n, v, s in zip(names, theta, std)},
        given_held={n: (float(v - z * s), float(v + z * s)) for n, v, s in zip(names, theta, given)},
        std=dict(zip(names, std.tolist())), identifiability=ident, residual_std=noise, correlation=correlation,
        samples=int(sum(b.features.shape[0] for b in problem.blocks)), level=level)


def _settled(bg, arrs: Sequence, records: Sequence, ident: Identifiability, window: int | None, quadrature: str,
             prior: float | None, problem: Problem | None = None) -> tuple:
    """The fit of the identified parameters, refitted without the one whose interval tells least while any
    tells less than the prior (judged at the fit: at a datasheet far off, the Jacobian promises more than the
    fit gives).  The problem, the relative estimates, their covariance, each ARR's noise and inflation, and
    the identifiability with the parameters held.  ``problem``: one already built, used if it holds exactly
    the identified parameters."""
    spread = math.inf if prior is None else prior
    while True:
        names = ident.identified
        if problem is None or problem.names != names:
            problem = windowed_problem(arrs, records, names, bg.parameters, window, bg.domains, quadrature)
        if not sum(b.features.shape[0] for b in problem.blocks):
            raise SettingError("records", "{setting}: no sample where every signal and derivative of the ARRs is "
                                          "known")
        x = _fit(problem, _bounds(bg, names, problem.nominal), spread)
        covariance, noise, correlation = fit_covariance(problem, x, spread)
        relative = np.sqrt(np.maximum(np.diag(covariance), 0.0))
        if prior is None or len(names) < 2 or relative.max() <= prior:
            return problem, x, covariance, noise, correlation, ident
        ident = _held(ident, names[int(np.argmax(relative))])


def _fit(problem: Problem, bounds: tuple, spread: float) -> np.ndarray:
    """The relative parameters that make the scaled residuals and the prior smallest."""
    # the prior on the logarithm of each relative value: a factor 2 above the datasheet costs what a factor 2
    # below does, and zero is infinitely far
    def residual(x):
        return np.concatenate([problem.residual(x), np.log(np.abs(x)) / spread])

    def jacobian(x):
        return np.vstack([problem.jacobian(x), np.diag(1.0 / x) / spread])

    return optimize.least_squares(residual, np.ones(len(problem.names)), jac=jacobian, bounds=bounds,
                                  x_scale="jac", method="trf", ftol=1e-14, xtol=1e-14, gtol=1e-14).x


def _held(ident: Identifiability, name: str) -> Identifiability:
    """``ident`` with ``name`` moved from the identified parameters to a weakly seen group of its own."""
    group = {"parameters": [name], "kept": name, "direction": {name: 1.0}, "weak": True,
             "expression": _weakly_seen([name])}
    return Identifiability([p for p in ident.identified if p != name], [*ident.combinations, group], ident.unseen,
                           ident.singular_values)


def _kept_uncertainty(arrs: Sequence, records: Sequence, names: list, kept: list, values: Mapping, x: np.ndarray,
                      window: int | None, domains: Mapping, quadrature: str, prior: float) -> np.ndarray:
    """What the datasheet's own uncertainty (``prior``) of the weakly seen parameters held at their datasheet
    values adds to the fitted ones' covariance: ``G diag(prior^2) G'``, ``G`` how the fit would move per relative
    change of a held one (``-(J'J)^-1 J' J_held`` at the fit).  Held without it, they would pass their
    datasheet error on to the others with intervals that do not know it."""
    both = windowed_problem(arrs, records, names + kept, values, window, domains, quadrature)
    jac = both.jacobian(np.concatenate([x, np.ones(len(kept))]))
    fitted, held = jac[:, :len(names)], jac[:, len(names):]
    moved = -np.linalg.pinv(fitted.T @ fitted + np.eye(len(names)) / prior ** 2) @ fitted.T @ held
    return prior ** 2 * moved @ moved.T


def _bounds(bg, names: list, nominal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each parameter's physical domain (:attr:`BondGraph.domains`), in relative terms, kept off its edge."""
    domains = bg.domains
    lower, upper = [], []
    for name, value in zip(names, nominal):
        lo, hi = domains.get(name, (-math.inf, math.inf))
        a, b = sorted((lo / value, hi / value)) if value else (-math.inf, math.inf)
        lower.append(a + 1e-9 if math.isfinite(a) else -np.inf)
        upper.append(b - 1e-9 if math.isfinite(b) else np.inf)
    return np.array(lower), np.array(upper)


# ------------------------------------------------------------------------------------------- boxes

def uncertainty_boxes(estimate: ParameterEstimate, method: str = "confidence", *,
                      per_record: Sequence[ParameterEstimate] = (), model=None, records: Sequence = (),
                      settings=None) -> dict:
    """Multiplicative boxes ``(lo, hi)`` about the estimates, for ``uncertainty=`` of the model's elements.

    ``"confidence"`` (the default): the estimate's confidence interval, ``(lo / value - 1, hi / value - 1)``:
    what the records leave unknown of each parameter (given the weakly seen ones, held at the datasheet with
    boxes of their own: :attr:`ParameterEstimate.given_held`).
    ``"records"``: the spread of the estimates made on each record alone (``per_record``, at least two),
    their range about the pooled estimate, widened by each one's own interval: what changes between days and
    operating points.
    With ``model`` (the datasheet model), a box that would reach out of its parameter's domain (a poorly seen
    positive parameter whose interval reaches below zero) is cut :data:`BOX_CUT` of the way short of the
    domain's edge, with a warning naming it: the model refuses such a box.
    ``"set-membership"``: the smallest boxes about the estimates in which every one of ``records`` (healthy,
    typically those of the fit) stays inside the thresholds of :func:`~diagnosis.detect` with ``settings``
    (:func:`~diagnosis.set_membership.set_membership_boxes`, a linear program), ``model`` being the datasheet
    model the estimate was made on: what the model's remaining error needs, no more.

    >>> fit = ParameterEstimate({"b": 2.0}, {"b": 1.0}, intervals={"b": (1.8, 2.3)}, std={"b": 0.1})
    >>> uncertainty_boxes(fit)
    {'b': (-0.1, 0.15)}
    """
    if method == "set-membership":
        if model is None or not records:
            raise SettingError("method", "{setting} 'set-membership' needs the model and the healthy records")
        return set_membership_boxes(estimate.model(model), records, estimate.estimated, settings=settings)
    if method == "confidence":
        boxes = {p: (round(lo / estimate.values[p] - 1.0, 12), round(hi / estimate.values[p] - 1.0, 12))
                 for p, (lo, hi) in {**estimate.intervals, **estimate.given_held}.items()}
        return boxes if model is None else _inside_domains(boxes, estimate.values, model.domains)
    if method == "records":
        if len(per_record) < 2:
            raise SettingError("method", "{setting} 'records' needs the estimates of at least two records")
        boxes = {}
        for p, value in ((p, estimate.values[p]) for p in estimate.intervals):
            seen = [r.intervals[p] for r in per_record if p in r.intervals]
            lo = min([a for a, _ in seen] + [estimate.intervals[p][0]])
            hi = max([b for _, b in seen] + [estimate.intervals[p][1]])
            boxes[p] = (lo / value - 1.0, hi / value - 1.0)
        return boxes if model is None else _inside_domains(boxes, estimate.values, model.domains)
    raise SettingError("method", f"{{setting}} must be 'confidence', 'records' or 'set-membership', got {method!r}")


#: A box cut to its parameter's domain stops this share of the way short of the domain's edge.
BOX_CUT = 1e-3


def _inside_domains(boxes: dict, values: Mapping, domains: Mapping) -> dict:
    """The boxes, each side cut to its parameter's (open) domain, with a warning naming those cut."""
    out, cut = {}, []
    for p, (lo, hi) in boxes.items():
        value = values[p]
        low, high = domains.get(p, (-math.inf, math.inf))
        sides = []
        for relative in (lo, hi):
            bound = value * (1.0 + relative)
            edge = low if bound <= low else high if bound >= high else None
            if edge is not None:
                relative = (edge / value - 1.0) * (1.0 - BOX_CUT)
                cut.append(p)
            sides.append(relative)
        out[p] = (min(sides), max(sides))
    if cut:
        names = ", ".join(dict.fromkeys(cut))
        warnings.warn(f"uncertainty box of {names} cut to its domain (the interval reaches past it)", stacklevel=3)
    return out
