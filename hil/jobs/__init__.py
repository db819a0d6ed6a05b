"""Jobs: one way to take a station and run a calibration, a verification or a MOVEB path on it.

The layer between the domain packages (campaign, store, verify, moveb) and the front-ends (cli, tui):
`hil.jobs.station` takes a station (lock, devices, controller check, robot identity, store);
`hil.jobs.calibration`, `hil.jobs.verification` and `hil.jobs.moveb` are functions over a typed request
that return an outcome carrying its exit code (`hil.jobs.outcome`). The front-ends map their options to
a request and show the outcome; they never import each other.

The face imports nothing: importing a command's module must not pay for the numerical libraries.
"""
