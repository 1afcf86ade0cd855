"""Altitude estimators of the papers and the baseline, on shared Kalman machinery.

The Kalman steps (:mod:`altfusion.estimators.kalman`) run compiled when the build compiled
them for this interpreter (:mod:`altfusion.compiled`)."""

from altfusion.compiled import compiled_path

__path__[:0] = compiled_path(__path__[0])
