"""Choosing measurement poses: observability indices, candidates, tabu search, bounds. Pure functions."""
