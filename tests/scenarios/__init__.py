"""Prognosis scenarios (issue 31): degradations simulated from the physics, run through ``bgphm prognose``."""
