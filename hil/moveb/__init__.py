"""MOVEB: error-controlled smooth trajectories (seed 001): programs, planning, timing, running.

May import: `hil.arm` (IK, safe targets), `hil.compensation` (joint paths), `hil.files`, `hil.errors`,
`hil.report`'s plot style and the drivers' typed errors; its run drives a station's devices handed to it
(`hil.cli.moveb` opens them).
"""
