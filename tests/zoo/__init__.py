"""The model zoo: systems written from textbooks and datasheets, each with its own reference physics."""
