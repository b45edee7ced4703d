"""Data files shipped with empact: default parameters, calibration targets, scenarios."""
