"""The error prognosis raises on bad input: :class:`PrognosisError`, a :class:`~bondgraph.errors.PHMError`.

Bad input to prognosis is a candidate, failure value, direction, degradation law, record, weight array,
filter option or model matrix that it cannot use.  The error is also a :class:`ValueError`, so code
written against the plain ``ValueError`` of earlier releases keeps working.

>>> from bondgraph import PHMError
>>> from prognosis import degradation_model
>>> try:
...     degradation_model("quadratic")
... except PHMError as error:
...     print(type(error).__name__, isinstance(error, ValueError))
PrognosisError True
"""

from __future__ import annotations

from bondgraph.errors import PHMError

__all__ = ["PrognosisError"]


class PrognosisError(PHMError, ValueError):
    """Bad input to prognosis: an option, array, model or candidate the call cannot use.

    The message names the option, parameter, ARR or array at fault.

    Examples
    --------
    >>> from prognosis.resampling import get_scheme
    >>> try:
    ...     get_scheme("bootstrap")
    ... except PrognosisError as error:
    ...     print(error)
    unknown resampling scheme 'bootstrap'; choose one of: multinomial, residual, stratified, systematic
    """
