"""Turning measurements into a model: tables, identification, model files, exports, synthetic truths.

* `measurements` — the measurements CSV (q1..q6, x, y, z, optionally d1..d6) read and written;
* `measurement_forms` — the other forms instruments write (degrees, URDF joint names, polar Hz/V/D,
  an orientation per pose, several markers), read into radians and metres;
* `identification` — tracker alignment, Levenberg–Marquardt on SE(3), outlier rejection, validation;
* `joint_error_request` — what ``--joint-errors`` / ``campaign.joint_errors`` ask for (none, auto, orders);
* `joint_error_selection` — which low-order joint errors the data support, by cross-validation;
* `model_file` — the ``hil-model/1`` and ``hil-truth/1`` JSON documents;
* `exports` — URDF, ROS kinematics YAML and JSON exports of a model;
* `urdf_rewrite` — a URDF with some joints' `<origin>` values spliced in, every other byte kept;
* `calibrated_urdf` — a URDF chain's calibrated placements written back into its own file;
* `controller_export` — the controller's own model as the ROS kinematics YAML UR's ur_calibration writes;
* `synthetic` — random realistic truths and simulated measurements (``hil synth``, the simulators);
* `stream_clocks` — the tracker's and the controller's clocks against the true time (the simulated
  station's truth) and the map between their stamps;
* `stream_join` — a sweep's joint and tracker streams joined in time: the clock map estimated from the
  data with its uncertainty, untrusted samples left out by reason;
* `synthetic_stream` — synthetic sweeps (a smooth joint path, both streams on their own clocks);
* `selection` — the glue to the `selector` package: hil's model as its `PoseModel`, ``hil select``.
* `urdf_selection` — an arm read from its URDF as the selector's `PoseModel` (``hil select --urdf``);
* `selection_parameters` — the parameters a design is made for: expected sizes, what a station observes.

No I/O with devices, no campaign state: pure computations on files and arrays.
May import: `hil.arm`, `hil.files`, `hil.errors`, `selector`, and `drivers.tracker.geometry` (the one
polar↔Cartesian conversion, for polar measurement files).
"""
