"""One base class, bondgraph.PHMError, for every error the toolkit raises on bad input."""

import numpy as np
import pytest

from bgphm.errors import UsageError
from bondgraph import (AlgebraicLoopError, BondGraph, CausalityError, EquationError, LawError, ModelError, PHMError,
                       SimulationError, simulate)
from bondgraph.io import ModelFileError, load_model
from bondgraph.library import rlc_circuit
from diagnosis import RecordError, as_record

ERRORS = [ModelError, LawError, ModelFileError, CausalityError, EquationError, AlgebraicLoopError, SimulationError,
          RecordError, UsageError]


@pytest.mark.parametrize("error", ERRORS, ids=lambda e: e.__name__)
def test_every_error_is_a_phm_error_and_still_a_value_error(error):
    assert issubclass(error, PHMError) and issubclass(error, ValueError)


def test_one_except_clause_catches_bad_models_records_files_and_simulations(tmp_path):
    def bad_model():
        BondGraph().add("X", "Q")

    def bad_record():
        as_record({"t": np.array([0.0, 1.0])}, ["omega"])

    def bad_file():
        load_model(tmp_path / "missing.json")

    def bad_simulation():
        simulate(rlc_circuit(), (0.0, 1.0), {})   # no value for the input V

    for action in (bad_model, bad_record, bad_file, bad_simulation):
        with pytest.raises(PHMError):
            action()
