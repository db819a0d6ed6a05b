"""Running a calibration campaign: plans say what to do, one engine says how, events flow out.

* `steps` — the plain steps a plan yields (move, settle, read joints, measure, checkpoint), dry runs
  and a whole plan's motion laid out along the routes the run takes (`hil.arm.routes`);
* `calibration_plan` — the calibration plan: bootstrap, select, warm up, measure, identify, validate;
* `sweep_plan`, `sweep_recording`, `sweep_rests`, `sweep_bootstrap`, `sweep_lines` — the sweep mode's
  tour and fit, a segment's recording, rests read off the streams' holds, the swept bootstrap, and
  the operator's words for its events;
* `warmup` — the warm-up before measuring and the drift watch of a reference pose while measuring;
  `reference_lines` — the operator's words for their events;
* `controller` — the controller's own kinematic model: the record kept, its error on the validation poses;
* `chooser` — the plan's pose chooser on a station (tabu calibration poses, random validation poses);
* `engine` — the state machine that executes a plan, and nothing else: pause, resume, abort,
  checkpoints, suspenders;
* `suspenders` — the station's faults mapped to pauses that clear by themselves or by the operator;
* `events` — the frozen dataclasses every subscriber (store, TUI, CLI printer) receives;
* `ids` — campaign ids (UTC start time and random bits), made here or by the store alike;
* `runner` — one campaign from devices to outcome, resumed from the store's state when asked.

May import: `hil.station`, `hil.calibration`, `hil.arm`, `hil.files`, `hil.errors`, `selector`, `drivers`.
Never the store, the report, the CLI or the TUI: they subscribe to its events.
"""
