"""docs/faults.md's all_fail criterion (PX4 EKF2's AllHgtFailReset) for an estimator whose
height reference failed with no third height sensor in range: the height follows the
reference (RMS error within the reference's offset plus 3x the nominal RMS), at most one
height reset, no NaN."""

import numpy as np

from altfusion.scores import follows_reference

TIME = np.arange(0.0, 300.0, 0.1)
START, AFTER = 130.0, 170.0
RNG = np.random.default_rng(3)
NOMINAL = 2.0 * RNG.standard_normal(TIME.size)          # nominal RMS ≈ 2 m
VALID = np.ones_like(TIME)


def judged(error, resets=None, offset=10.0):
    resets = np.zeros_like(TIME) if resets is None else resets
    return follows_reference(TIME, error, resets, NOMINAL, VALID, offset, START, AFTER)


def test_a_height_on_its_references_offset_passes():
    """GNSS +10 m followed: about 10.2 m RMS against 10 + 3 x 2 = 16 m."""
    error = np.where(TIME >= START, 10.0, 0.0) + 2.0 * RNG.standard_normal(TIME.size)
    passed, measured = judged(error)
    assert passed, measured
    assert "0 height reset(s)" in measured


def test_a_height_beyond_the_offset_and_3x_the_nominal_rms_fails():
    error = np.where(TIME >= START, 20.0, 0.0)
    assert not judged(error)[0]
    assert judged(error, offset=15.0)[0]                 # 20 m <= 15 + 3 x 2


def test_one_height_reset_passes_two_fail():
    error = np.where(TIME >= START, 10.0, 0.0)
    one = np.where(TIME >= 131.0, 1.0, 0.0)
    two = one + np.where(TIME >= 150.0, 1.0, 0.0)
    early = np.where(TIME >= 50.0, 1.0, 0.0) + one       # a reset before the fault: not its
    assert judged(error, one)[0] and judged(error, early)[0]
    passed, measured = judged(error, two)
    assert not passed and "2 height reset(s)" in measured


def test_a_nan_fails():
    error = np.where(TIME >= START, 10.0, 0.0)
    error[2000] = np.nan
    assert judged(error) == (False, "NaN or infinite error")
