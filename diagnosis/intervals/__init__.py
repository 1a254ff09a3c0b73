r"""Interval arithmetic with outward rounding for robust fault-detection thresholds.

The uncertain part :math:`\Psi_2` of an interval-valued ARR (Jha et
al. (2016), section 2.3) is an expression in point-valued signals, point-valued
nominal parameters and interval-valued multiplicative uncertainties
:math:`[\delta_\theta]`. Its range :math:`[\underline B(t), \overline B(t)]`
over the uncertainty box is the detection threshold: a fault is declared when
:math:`-r_n(t)` leaves it (eqs. 16-20).

Natural interval extension
--------------------------
:func:`compile_interval` replaces every real operation of the sympy expression
by its interval counterpart (Jha et al. (2016), Appendix A, Definition A.2). Each
interval operation encloses the exact range of the real operation over its
arguments, so the result is a rational interval function, inclusion isotonic
(Moore; Lemma A.3.1), and by the fundamental theorem of interval analysis
(Theorem A.1)

.. math:: f(X_1, \dots, X_n) \subseteq F(X_1, \dots, X_n).

The enclosure is sound but overestimates when an interval symbol occurs more
than once (the *dependency problem*): every occurrence is treated as an
independent variable, so :math:`\delta - \delta` over :math:`[-1, 1]` gives
:math:`[-2, 2]` instead of :math:`[0, 0]`. For the BG-LFT form
:math:`g_0 + \sum_i \delta_i g_i` each :math:`\delta_i` occurs once after
:func:`sympy.collect`; :func:`affine_range` evaluates that collected form,
whose natural extension is the exact range up to rounding.

Outward rounding
----------------
Every computed lower bound ``l`` becomes ``np.nextafter(l, -inf)`` and every
upper bound ``h`` becomes ``np.nextafter(h, +inf)``, bit for bit; on arrays the
step is an integer operation on the bit pattern, about twice as fast as
numpy's ``nextafter``, which calls libm once per element. One ulp suffices for
``+ - * /`` and ``sqrt``, which IEEE 754 rounds correctly (the exact result
lies within half an ulp of the computed one). numpy's ``exp``, ``log``,
``tanh``, ``sin``, ``cos`` and ``power`` are not correctly rounded (glibc
documents errors of 1 to 2 ulps, numpy's SIMD kernels up to 4), so their
bounds move out by ``(2 k + 1) eps |x| + (k + 1) tiny`` with
``k =`` :data:`TRANSCENDENTAL_ULPS` (``eps = 2**-52``, ``tiny = 2**-1074``):
at least ``k`` ulps even across a power of two, plus one for the rounding of
the widening itself. Integer powers are products of outward-rounded interval
multiplications (square-and-multiply), so they need no error model. Exact
results are not widened: negation, ``abs``, ``sign``, ``min``, ``max``, the
lower bound 0 of an even power, adding the constant 0 and multiplying by the
constants 0, 1 and -1. A constant that is not a double (``1/3``,
``pi``, a sympy ``Float`` of more than 53 bits) becomes the interval between
the two doubles around it.

Modules
-------
The layers import downward only: ``rounding`` (outward rounding, warning
bookkeeping) -> ``kernels`` (interval operations on ``(lo, hi)`` pairs) ->
``interval`` (:class:`Interval`, :class:`IntervalArray`) -> ``functions``
(elementwise functions) -> ``compiler`` (sympy expressions). Import the public
names from this package.

Examples
--------
>>> from diagnosis.intervals import Interval
>>> delta = Interval(-1.0, 1.0)
>>> delta - delta
Interval(-2.0000000000000004, 2.0000000000000004)
>>> Interval(0.1, 0.1) + Interval(0.2, 0.2)
Interval(0.3, 0.3000000000000001)
"""

from .compiler import affine_range, compile_interval, enclose, product_parts
from .functions import absolute, cos, exp, log, maximum, minimum, power, sign, sin, sqrt, tanh
from .interval import Interval, IntervalArray
from .rounding import TRANSCENDENTAL_ULPS, IntervalWarning

__all__ = [
    "TRANSCENDENTAL_ULPS",
    "Interval",
    "IntervalArray",
    "IntervalWarning",
    "absolute",
    "affine_range",
    "compile_interval",
    "cos",
    "enclose",
    "exp",
    "log",
    "maximum",
    "minimum",
    "power",
    "product_parts",
    "sign",
    "sin",
    "sqrt",
    "tanh",
]
