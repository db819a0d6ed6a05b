"""The ISO 9283 pose test (``hil verify``): how accurately and repeatably the arm reaches five poses.

The test cube and its poses P1–P5 (`hil.verify.cube`), the standard's formulas for position accuracy AP
and repeatability RP (`hil.verify.accuracy`), the joint targets of both modes — the controller's own
model (uncompensated) and hil's calibrated one (compensated) — checked before anything moves
(`hil.verify.design`), the test as a plan of steps for the campaign engine
(`hil.verify.verification_plan`), the result document (`hil.verify.result`) and a verification on a
station's devices, stored like a
campaign and resumable (`hil.verify.session`).

May import: `hil.arm`, `hil.calibration`, `hil.campaign`, `hil.compensation`, `hil.station`,
`hil.store`, `hil.errors`; nothing below it imports it (the CLI and the report read it).
"""
