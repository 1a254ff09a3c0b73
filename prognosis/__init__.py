"""prognosis: fault model, particle filters, RUL prediction, metrics (issue 4)."""
