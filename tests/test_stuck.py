"""A reading repeated bit for bit is stuck (estimators/stuck.py)."""

import numpy as np

from altfusion.estimators.stuck import StuckCheck


def test_a_reading_is_stuck_from_its_limit_th_repetition_until_it_changes():
    check = StuckCheck(3)
    verdicts = [check.stuck(v) for v in (1.0, 1.0, 1.0, 1.0, 1.0, 2.0, 2.0)]
    assert verdicts == [False, False, False, True, True, False, False]


def test_a_noisy_quantized_reading_is_never_stuck_and_a_limit_of_zero_is_off():
    """A 5 mm laser read to the millimetre at 15 m: 100 000 samples, never ten repeats
    (two successive readings coincide about 6 % of the time)."""
    readings = np.round(15.0 + 0.005 * np.random.default_rng(2).standard_normal(100_000), 3)
    check = StuckCheck(10)
    assert not any(check.stuck(float(v)) for v in readings)
    off = StuckCheck(0)
    assert not any(off.stuck(0.0) for _ in range(100))
