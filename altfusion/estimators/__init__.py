"""Altitude estimators of the papers and the baseline, on shared Kalman machinery."""
