"""Trajectory validation with simulated accelerometers and a Kalman filter
(paper 000, section 3 and eqs 11-21), imported as ``paragym.validation``."""
