"""The station a job runs on: its configuration file, its devices, and the simulated station.

* `config` — ``station.toml`` parsed and validated key by key (`station.example.toml` documents it);
* `devices` — the robot and tracker drivers built from a configuration and opened together;
* `simulated` — the simulated station (protocol-level simulators in their own processes) and the
  configuration that points at it.

Both a calibration campaign and a MOVEB run use a station, so it sits below both.
May import: `hil.arm`, `hil.calibration` (truth files), `hil.files`, `hil.errors`, `drivers`, `mocks`.
"""
