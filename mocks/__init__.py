"""Protocol-level simulators of a UR controller and a GeoCOM tracker sharing one simulated world."""
