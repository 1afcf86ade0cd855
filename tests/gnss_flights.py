"""Flights over a GNSS whose height error wanders slowly: the harnesses of
``tests/test_gnss_slow_error.py``, ``tests/test_stuck.py`` and ``benchmarks/gnss_slow_error.py``."""

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from stream_feeder import StreamFeeder

from altfusion.constants import ISA_LAPSE_RATE, ISA_P0, ISA_T0
from altfusion.physics.barometric import pressure_at, temperature_at
from altfusion.physics.gauss_markov import gauss_markov_step

SLOW, TAU, WHITE = 1.5, 60.0, 0.3
"""The receiver's height error: a first-order Gauss-Markov error of 1.5 m and 60 s (started
from its stationary distribution) under 0.3 m of white noise, the GnssReceiver's ``gm_std``,
``gm_time_constant`` and ``user_range_error``."""

SETTLE = 20.0
"""Seconds after the start left out of what a flight returns (the filter's start)."""


class GaussMarkov:
    """A first-order Gauss-Markov error of σ ``std`` and time constant ``tau``, sampled every
    ``period`` s from ``rng``, started from its stationary distribution (one draw now)."""

    def __init__(self, std: float, tau: float, period: float, rng: np.random.Generator):
        self.std, self.rng = std, rng
        self.decay = math.exp(-period / tau)
        self.value = std * rng.standard_normal()

    def step(self) -> float:
        """The error one period later."""
        self.value = gauss_markov_step(self.value, self.decay, self.std,
                                       self.rng.standard_normal())
        return self.value


def air_data(h: float) -> dict[str, float]:
    """The baro's pressure and temperature at height ``h`` in the standard atmosphere (the
    estimators that read them)."""
    return {"baro_p": pressure_at(h, ISA_P0, ISA_T0, ISA_LAPSE_RATE),
            "baro_T": temperature_at(h, ISA_T0, ISA_LAPSE_RATE)}


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
    slow = GaussMarkov(slow_std, TAU, 0.2, rng)
    flight = Flight()
    for n in range(round(seconds / 0.1)):
        t = 0.1 * (n + 1)
        h, a = 100.0 + 10.0 * math.sin(t / 5.0), -0.4 * math.sin(t / 5.0)
        gps = None
        if n % 2 == 0:
            gps = {"gps_h": h + slow.step() + white * rng.standard_normal(), "gps_vdop": 1.0,
                   "gps_nsat": 10, "gps_fix": True}
        feed.step(baro={"baro_h": h + 3.0 + 0.5 * rng.standard_normal(), **air_data(h)},
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


@dataclass
class Hover:
    """What :func:`nmea_receiver_hover` saw of the estimator."""

    notes: list[str]
    """Its notes about the GNSS."""
    rejected: int
    """GNSS height samples rejected."""
    isolated: float
    """Seconds with the GNSS height isolated (``status``)."""


def nmea_receiver_hover(estimator, seed: int = 1, wander: float = 0.3, tau: float = 60.0,
                        with_speed: bool = False, climb: float = 0.0,
                        seconds: float = 120.0) -> Hover:
    """``estimator`` (a core, step 0.01 s) hovering at 100 m for ``seconds`` (from 60 s on
    climbing at ``climb``), fed a baro of 0.1 m noise at 50 Hz, an accelerometer of
    0.05 m/s² at 100 Hz and a smooth receiver's GNSS height at 10 Hz: its error a
    Gauss-Markov wander of ``wander`` and ``tau`` under 2 cm of noise, read to 0.1 m (NMEA
    GGA's resolution), so that a reading repeats for a second or more; its vertical speed
    (``with_speed``) 5 cm/s of noise read to 1 cm/s, else left unconnected (reads 0); seed
    ``seed``."""
    feeder, rng = StreamFeeder(estimator), np.random.default_rng(seed)
    error = GaussMarkov(wander, tau, 0.1, rng)
    notes, isolated = [], 0
    for n in range(round(seconds / 0.01)):
        h, vz = (100.0, 0.0) if n < 6000 else (100.0 + climb * (n - 6000) * 0.01, climb)
        samples = {"acc": {"acc_z": 0.05 * rng.standard_normal()}}
        if n % 2 == 0:
            samples["baro"] = {"baro_h": h + 0.1 * rng.standard_normal(), **air_data(h)}
        if n % 10 == 0:
            samples["gps"] = {"gps_h": round((h + error.step() + 0.02 * rng.standard_normal())
                                             / 0.1) * 0.1,
                              "gps_vdop": 1.0, "gps_nsat": 10, "gps_fix": True}
            if with_speed:
                samples["gps"]["gps_vz"] = round(vz + 0.05 * rng.standard_normal(), 2)
        feeder.step(**samples)
        notes += [note for note in estimator.take_notes() if "gps" in note]
        isolated += bool(estimator.status & estimator.aid["gps"].isolated_mask)
    return Hover(notes, estimator.aid["gps"].rejected, 0.01 * isolated)
