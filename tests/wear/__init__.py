"""Wear scenarios for prognosis: degradations simulated from the physics, run through ``bgphm prognose``."""
