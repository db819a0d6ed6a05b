"""MOVEB: error-controlled smooth trajectories (seed 001): programs, planning, timing, running."""
