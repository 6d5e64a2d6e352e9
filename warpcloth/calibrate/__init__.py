"""Calibration against measurements: KES-FB materials, the motion fit, the clamp-motion
fit, swing metrics, and the exact references the model is checked against."""
