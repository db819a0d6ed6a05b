"""Talking to real hardware: the UR robot (ur_rtde) and the laser tracker (GeoCOM over pyserial)."""
