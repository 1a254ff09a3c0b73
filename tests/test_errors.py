"""One base class, bondgraph.PHMError, for every error the toolkit raises on bad input."""

import numpy as np
import pytest

from bgphm.errors import UsageError
from bondgraph import (AlgebraicLoopError, BondGraph, CausalityError, EquationError, FmuError, LawError, ModelError,
                       PHMError, SimulationError, simulate)
from bondgraph.io import ModelFileError, load_model
from bondgraph.library import rlc_circuit
from diagnosis import RecordError, as_record
from prognosis import PrognosisError

ERRORS = [ModelError, LawError, ModelFileError, CausalityError, EquationError, AlgebraicLoopError, SimulationError,
          FmuError, RecordError, UsageError, PrognosisError]


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


def _project_classes(base):
    """Every class deriving from ``base`` defined in a module of the four packages."""
    import importlib
    import inspect
    import pkgutil

    found = set()
    for package_name in ("bondgraph", "diagnosis", "prognosis", "bgphm"):
        package = importlib.import_module(package_name)
        for info in pkgutil.walk_packages(package.__path__, package_name + "."):
            if info.name.endswith("__main__"):
                continue
            module = importlib.import_module(info.name)
            found |= {obj for _, obj in inspect.getmembers(module, inspect.isclass)
                      if issubclass(obj, base) and obj.__module__.split(".")[0] == package_name}
    return found


def test_every_warning_of_the_toolkit_is_a_phm_warning():
    from bondgraph import PHMWarning

    warnings_found = _project_classes(Warning)
    assert len(warnings_found) >= 7   # ARR, record, interval, filter, identification, sampler, metric
    assert all(issubclass(w, PHMWarning) for w in warnings_found), sorted(
        w.__name__ for w in warnings_found if not issubclass(w, PHMWarning))


def test_every_public_error_of_the_toolkit_is_a_phm_error():
    errors = {e for e in _project_classes(Exception) if not issubclass(e, Warning) and not e.__name__.startswith("_")}
    assert set(ERRORS) <= errors
    outside = sorted(e.__name__ for e in errors if not issubclass(e, PHMError))
    assert not outside, outside
