"""What the arm is: the robot catalog, its geometry, forward and inverse kinematics, and safe targets.

* `catalog` — the UR models hil knows (nominal DH, joint limits, speeds, ur_description names);
* `geometry` — the URDF-convention joint origins, flange, SMR and tracker pose of one arm;
* `kinematics` — batched forward kinematics and identification Jacobians (pinocchio), the parameter
  vector and its identifiable subset;
* `ik` — inverse kinematics of a (calibrated) model, for tool paths;
* `safety` — a motion target checked against the joint limits and the keep-in box, never clamped.
* `blas_threads` — one BLAS thread per process: the model's matrices are small, and OpenBLAS's threads
  only slow them (the CLI and the simulators set it when they start).

One kinematic model serves the selector, identification, the simulators and the exports.
May import: `hil.errors`, `hil.files`. Imported by every package above it, and by `mocks`.
"""
