"""Putting a calibration to work: targets solved with hil's model, sent in the controller's terms."""
