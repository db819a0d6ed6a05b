"""What the arm is: the robot catalog, its geometry, forward and inverse kinematics, and safe targets.

* `catalog` — the UR models hil knows (nominal DH, joint limits, speeds, ur_description names);
* `chain` — the kinematic structure of one serial arm (joint kinds RZ/PZ, nominal origins, limits),
  a catalog UR's (`ur_chain`) or a URDF's;
* `urdf_chain` — a chain from a URDF between a base and a tip link (`chain_from_urdf`), pinocchio parsing;
* `geometry` — the URDF-convention joint origins, flange, SMR and tracker pose of one arm;
* `kinematics` — batched forward kinematics and identification Jacobians (pinocchio), the parameter
  vector and its identifiable subset;
* `joint_errors` — angle-dependent joint errors and lost motion (the model and its JSON blocks);
* `joint_error_columns` — their low orders as identification parameters: names, columns, updates;
* `joint_directions` — which way each joint last moved (the side its lost motion lags to), the rule
  the simulated arm and the sweep's fit both follow;
* `gravity`, `dynamics` — the torques a (moving) arm's joints hold and the link lag c ⊙ τ they cause
  (pinocchio's gravity and inverse dynamics on UR's published masses), and the joint modes that bound
  where that quasi-static lag holds;
* `ik` — inverse kinematics of a (calibrated) model, for tool paths;
* `safety` — a motion target checked against the joint limits and the keep-in box, never clamped;
* `self_collision` — whether a posture folds the arm onto itself (the selector's link capsules on
  these kinematics' joint frames);
* `urdf_collision` — self-collision of a URDF arm: its own collision geometry checked in batches
  (pinocchio/coal), capsules around the chain's links where it has none;
* `routes` — how the arm gets to a target inside the keep-in box: straight, or the quickest safe
  detour (home, upright and folded transit postures), as the campaign moves and its dry run shows;
* `blas_threads` — one BLAS thread per process: the model's matrices are small, and OpenBLAS's threads
  only slow them (the CLI and the simulators set it when they start).

One kinematic model serves the selector, identification, the simulators and the exports.
May import: `hil.errors`, `hil.files`, and `selector` (its link capsules, for `self_collision`).
Imported by every package above it, and by `mocks`.
"""
