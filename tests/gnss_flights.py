"""Flights over a GNSS whose height error wanders slowly: the harnesses of
``tests/test_gnss_slow_error.py`` and ``benchmarks/gnss_slow_error.py``."""

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from stream_feeder import StreamFeeder

SLOW, TAU, WHITE = 1.5, 60.0, 0.3
"""The receiver's height error: a first-order Gauss-Markov error of 1.5 m and 60 s (started
from its stationary distribution) under 0.3 m of white noise, the GnssReceiver's ``gm_std``,
``gm_time_constant`` and ``user_range_error``."""

SETTLE = 20.0
"""Seconds after the start left out of what a flight returns (the filter's start)."""


@dataclass
class Flight:
    """What an estimator gave after :data:`SETTLE`, per 0.1 s step."""

    errors: list[float] = field(default_factory=list)
    """h_est - h, m."""
    stds: list[float] = field(default_factory=list)
    """h_std, m."""
    heights: list[float] = field(default_factory=list)
    """h_est, m."""
    valid: list[bool] = field(default_factory=list)
    """h_valid."""

    def coverage(self) -> float:
        """The fraction of valid steps with |e| <= 2 h_std."""
        hits = [abs(e) <= 2.0 * s for e, s, v in zip(self.errors, self.stds, self.valid,
                                                      strict=True) if v]
        return float(np.mean(hits)) if hits else math.nan


def wave_flight(estimator, seed: int, seconds: float = 300.0, slow_std: float = SLOW,
                white: float = WHITE, each_step: Callable[[object], None] | None = None,
                ) -> Flight:
    """``estimator`` (a core, step 0.1 s) over ±10 m waves about 100 m (period 31 s), fed a
    0.5 m baro 3 m off and an accelerometer of 0.05 m/s² at 10 Hz and, at 5 Hz, a GNSS height
    with a Gauss-Markov error of ``slow_std`` and :data:`TAU` under ``white`` noise (no
    vertical speed); seed ``seed`` (the same draws whatever the estimator). ``each_step`` is
    called with the estimator after every step."""
    feed, rng = StreamFeeder(estimator), np.random.default_rng(seed)
    decay = math.exp(-0.2 / TAU)
    slow = slow_std * rng.standard_normal()
    flight = Flight()
    for n in range(round(seconds / 0.1)):
        t = 0.1 * (n + 1)
        h, a = 100.0 + 10.0 * math.sin(t / 5.0), -0.4 * math.sin(t / 5.0)
        gps = None
        if n % 2 == 0:
            slow = decay * slow + slow_std * math.sqrt(1.0 - decay**2) * rng.standard_normal()
            gps = {"gps_h": h + slow + white * rng.standard_normal(), "gps_vdop": 1.0,
                   "gps_nsat": 10, "gps_fix": True}
        feed.step(baro={"baro_h": h + 3.0 + 0.5 * rng.standard_normal(),
                        "baro_p": 101325.0 * (1.0 - 2.25577e-5 * h) ** 5.25588,
                        "baro_T": 288.15 - 0.0065 * h},
                  acc={"acc_z": a + 0.05 * rng.standard_normal()}, gps=gps)
        estimator.take_notes()
        if each_step is not None:
            each_step(estimator)
        if t > SETTLE:
            flight.errors.append(estimator.h_est - h)
            flight.stds.append(estimator.h_std)
            flight.heights.append(estimator.h_est)
            flight.valid.append(bool(estimator.h_valid))
    return flight


def smooth_receiver_hover(estimator, seed: int, seconds: float = 120.0, slow_std: float = 0.5,
                          tau: float = 30.0) -> tuple[int, float]:
    """``estimator`` (a core, step 0.02 s) hovering at 100 m, fed a 0.1 m baro and an
    accelerometer of 0.05 m/s² at 50 Hz and, at 10 Hz, a smooth receiver's GNSS height: a
    Gauss-Markov error of ``slow_std`` and ``tau`` under 0.02 m of white noise, read to
    0.1 m (NMEA GGA); seed ``seed``. Returns the GNSS samples rejected and the seconds its
    ``status`` had it isolated."""
    feed, rng = StreamFeeder(estimator), np.random.default_rng(seed)
    decay = math.exp(-0.1 / tau)
    slow = slow_std * rng.standard_normal()
    isolated = 0
    for n in range(round(seconds / 0.02)):
        gps = None
        if n % 5 == 0:
            slow = decay * slow + slow_std * math.sqrt(1.0 - decay**2) * rng.standard_normal()
            gps = {"gps_h": round((100.0 + slow + 0.02 * rng.standard_normal()) / 0.1) * 0.1,
                   "gps_vdop": 1.0, "gps_nsat": 10, "gps_fix": True}
        feed.step(baro={"baro_h": 100.0 + 0.1 * rng.standard_normal(), "baro_p": 100129.0,
                        "baro_T": 287.5},
                  acc={"acc_z": 0.05 * rng.standard_normal()}, gps=gps)
        estimator.take_notes()
        isolated += bool(estimator.status & estimator.aid["gps"].isolated_mask)
    return estimator.aid["gps"].rejected, 0.02 * isolated
