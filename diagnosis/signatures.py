"""Structural fault signatures of a set of ARRs.

The fault signature matrix has a row per fault candidate and a column per ARR.
The candidates are the element parameters (entry 1 when the ARR's nominal part
depends on the parameter) and, by default, the sensors (``sensor <signal>``:
entry 1 when the ARR reads the signal, on which a sensor bias or drift acts).
A fault is *detectable* (Mb = 1) when some ARR is sensitive to it and
*isolable* (Ib = 1) when, moreover, no other row has the same signature.

Example
-------
>>> from bondgraph.library import dc_motor
>>> from diagnosis import derive_arrs
>>> print(signature_matrix(derive_arrs(dc_motor())))
              ARR_1_e  ARR_1_m  Mb  Ib
R_a                 1        0   1   0
L_a                 1        0   1   0
k_m                 1        1   1   0
J                   0        1   1   0
b                   0        1   1   0
sensor i            1        1   1   0
sensor omega        1        1   1   0
>>> print(signature_matrix(derive_arrs(dc_motor(), max_order=2)))   # two ARRs of second order isolate k_m
              ARR_1_e  ARR_1_m  ARR_MSO_1  ARR_MSO_2  Mb  Ib
R_a                 1        0          1          1   1   0
L_a                 1        0          1          1   1   0
k_m                 1        1          1          1   1   1
J                   0        1          1          1   1   0
b                   0        1          1          1   1   0
sensor i            1        1          0          1   1   1
sensor omega        1        1          1          0   1   1
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.optimize import Bounds, LinearConstraint, milp

from .structural import sensor_fault

__all__ = ["SignatureMatrix", "signature_matrix"]


@dataclass(frozen=True)
class SignatureMatrix:
    """Fault signature matrix with detectability and isolability per row.

    Attributes
    ----------
    rows : tuple of str
        Fault candidates: parameters, then sensors (``sensor <signal>``).
    columns : tuple of str
        ARR names.
    matrix : ndarray of int (rows, columns)
        1 where the ARR's nominal part depends on the parameter, or reads the sensor's signal.

    Examples
    --------
    Returned by :func:`signature_matrix`:

    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> signatures = signature_matrix(derive_arrs(rlc_circuit()))
    >>> signatures.rows, signatures.columns, signatures.matrix.tolist()
    (('R', 'L', 'C', 'sensor i', 'sensor v_C'), ('ARR_J1', 'ARR_J0'), [[1, 0], [1, 0], [0, 1], [1, 1], [1, 1]])
    >>> signatures.detectable.tolist(), signatures.isolable.tolist()   # R and L share a signature, so do the sensors
    ([1, 1, 1, 1, 1], [0, 0, 1, 0, 0])
    >>> signatures.row("C")
    {'ARR_J1': 0, 'ARR_J0': 1}
    """

    rows: tuple
    columns: tuple
    matrix: np.ndarray

    @property
    def detectable(self) -> np.ndarray:
        """Mb per row: 1 if at least one ARR is sensitive."""
        return self.matrix.any(axis=1).astype(int)

    @property
    def isolable(self) -> np.ndarray:
        """Ib per row: 1 if detectable and its signature differs from every other row's."""
        if not len(self.matrix):
            return np.zeros(0, int)
        # rows grouped by signature in one sort, not compared pairwise: a 200-stage chain has 800 rows
        _, group, count = np.unique(self.matrix, axis=0, return_inverse=True, return_counts=True)
        return ((count[group.reshape(-1)] == 1) & self.matrix.any(axis=1)).astype(int)

    def fewest_tests(self) -> SignatureMatrix:
        """The same rows over the fewest columns (ARRs) that keep what all of them achieve: every detectable
        fault still seen by one, every pair of faults with different signatures still told apart by one.

        A set cover solved exactly as an integer program (scipy's HiGHS): a column per ARR, a constraint per
        detectable row and per pair of distinct signatures.  Among equally few, HiGHS's choice.

        >>> m = SignatureMatrix(("a", "b", "c"), ("r1", "r2", "r3"), np.array([[1, 1, 0], [1, 0, 1], [0, 1, 1]]))
        >>> m.fewest_tests().columns   # two ARRs give three distinct nonzero signatures
        ('r1', 'r2')
        """
        needs = _covering_needs(self.matrix)
        if not needs.shape[0]:
            return SignatureMatrix(self.rows, (), self.matrix[:, :0])
        columns = self.matrix.shape[1]
        found = milp(c=np.ones(columns), constraints=LinearConstraint(needs, lb=1, ub=np.inf),
                     integrality=np.ones(columns), bounds=Bounds(0, 1))
        if found.x is None:  # never for a feasible cover (all the columns are one); say so rather than guess
            warnings.warn(f"fewest_tests: the integer program stopped ({found.message}); every ARR kept",
                          stacklevel=2)
            return self
        chosen = np.flatnonzero(np.round(found.x) > 0)
        return SignatureMatrix(self.rows, tuple(self.columns[j] for j in chosen), self.matrix[:, chosen])

    def row(self, name: str) -> dict:
        """The signature of one parameter: ARR name -> 0/1."""
        return dict(zip(self.columns, self.matrix[self.rows.index(name)].tolist()))

    def to_dict(self) -> dict:
        """The matrix as plain lists for JSON: ``rows``, ``columns``, ``matrix`` and the ``Mb`` and ``Ib`` columns."""
        return {"rows": list(self.rows), "columns": list(self.columns), "matrix": self.matrix.tolist(),
                "Mb": self.detectable.tolist(), "Ib": self.isolable.tolist()}

    def __str__(self) -> str:
        width = max(len(str(r)) for r in self.rows) if self.rows else 1
        columns = [str(c) for c in self.columns] + ["Mb", "Ib"]
        lines = [" " * width + "".join(f"  {c:>{max(len(c), 2)}}" for c in columns)]
        table = np.column_stack([self.matrix, self.detectable, self.isolable]) if self.rows else []
        for name, values in zip(self.rows, table):
            lines.append(f"{str(name):<{width}}" + "".join(f"  {v:>{max(len(c), 2)}}" for c, v in zip(columns, values)))
        return "\n".join(lines)


def _covering_needs(matrix: np.ndarray):
    """A sparse 0/1 matrix, a row per need and a column per ARR: the ARRs that see a detectable fault, and
    those that tell apart two distinct signatures (pairs of distinct rows, duplicates counted once)."""
    detectable = matrix[matrix.any(axis=1)]
    distinct = np.unique(matrix, axis=0)
    first, second = np.triu_indices(distinct.shape[0], k=1)
    needs = [sparse.csr_matrix(detectable)]
    for start in range(0, first.size, 20_000):  # in blocks: a 200-stage chain has some 300,000 pairs
        part = slice(start, start + 20_000)
        needs.append(sparse.csr_matrix((distinct[first[part]] != distinct[second[part]]).astype(int)))
    return sparse.vstack(needs, format="csr")


def signature_matrix(arrs: Sequence, rows: Sequence[str] | None = None, *, sensor_faults: bool = True
                     ) -> SignatureMatrix:
    """The fault signature matrix of ``arrs``.

    Parameters
    ----------
    arrs : sequence of ARR
    rows : sequence of str, optional
        Faults to list: parameters, and sensors as ``"sensor <signal>"``; default: every element
        parameter of the model, in model order, so that a fault no ARR can see shows as ``Mb = 0``,
        then every sensor.
    sensor_faults : bool
        List the sensors in the default rows (on by default); False assumes healthy sensors.

    Returns
    -------
    SignatureMatrix

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> arrs = derive_arrs(rlc_circuit())
    >>> print(signature_matrix(arrs, rows=["C", "R"]))   # without L, R is isolable
       ARR_J1  ARR_J0  Mb  Ib
    C       0       1   1   1
    R       1       0   1   1
    >>> signature_matrix(arrs[:1], rows=["R", "C"]).to_dict()["Mb"]   # the loop ARR alone cannot see C
    [1, 0]
    """
    if rows is None:
        rows = list(dict.fromkeys(p for arr in arrs for p in arr.candidates))
        if sensor_faults:
            rows += list(dict.fromkeys(sensor_fault(s) for arr in arrs for s in arr.sensors))
    read = [{sensor_fault(s) for s in arr.signals} for arr in arrs]
    matrix = np.array([[int(p in arr.parameters or p in signals) for arr, signals in zip(arrs, read)] for p in rows],
                      dtype=int)
    matrix = matrix.reshape(len(rows), len(arrs))
    return SignatureMatrix(tuple(rows), tuple(arr.name for arr in arrs), matrix)
