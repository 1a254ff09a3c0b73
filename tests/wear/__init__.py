"""Wear scenarios for prognosis (issue 31): degradations simulated from the physics, run through ``bgphm prognose``."""
