"""Every estimator over a GNSS whose height error wanders slowly, told the receiver's σ as a
datasheet gives it. Run by hand (never as a test):

    python benchmarks/gnss_slow_error.py [--seeds 12]

The flight of ``tests/gnss_flights.py``: ±10 m waves about 100 m, a 0.5 m baro 3 m off and
a 0.05 m/s² accelerometer at 10 Hz, a GNSS at 5 Hz whose height error is a Gauss-Markov
error of 1.5 m and 60 s under 0.3 m of white noise (GnssReceiver's ``gm_std``,
``gm_time_constant``, ``user_range_error``), 300 s, estimators stepped at 0.1 s. Each
estimator is told the noises as ``altfusion evaluate --told noise`` tells them
(``evaluation.scenarios.noise_parameters``), the GNSS's being the datasheet's
√(0.3² + 1.5²) = 1.53 m; AltitudeEKF also told the slow error apart (``gps_noise`` 0.3,
``gps_slow_error`` 1.5). Printed per estimator: RMS error, median h_std and the coverage of
|e| <= 2 h_std over the valid steps after 20 s (an honest h_std: 85-99.5 %). XuSHAEKF is
left out: its height is the laser's, within 25 m of the ground.
"""

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from altfusion.estimators.registry import ESTIMATOR_CLASSES
from altfusion.evaluation.scenarios import EstimatorInfo, noise_parameters

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from gnss_flights import SLOW, WHITE, wave_flight  # noqa: E402

NOISE = {"baro_noise": 0.5, "gps_noise": math.hypot(WHITE, SLOW), "acc_noise": 0.05}
"""The noises told, 1σ, by their contract names."""

CASES = [(name, None) for name in ("BaselineKF", "HajiyevAdaptiveEstimator",
                                    "WhangGAEstimator", "BaoDriftEstimator", "YangFusionKF",
                                    "AltitudeEKF")]
CASES.append(("AltitudeEKF", {"gps_noise": WHITE, "gps_slow_error": SLOW}))


def told(name: str, extra: dict | None) -> dict:
    """The parameters of estimator ``name``: the noises, then ``extra``."""
    cls = ESTIMATOR_CLASSES[name]
    info = EstimatorInfo(name, Path(), cls, frozenset(cls.Params.__dataclass_fields__))
    return noise_parameters(info, NOISE) | (extra or {})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=12)
    args = parser.parse_args()
    print(f"{'estimator':26s} {'told':34s} {'RMS m':>6s} {'h_std m':>8s} {'coverage':>8s}")
    for name, extra in CASES:
        cls = ESTIMATOR_CLASSES[name]
        params = told(name, extra)
        errors, stds, hits = [], [], []
        for seed in range(args.seeds):
            flight = wave_flight(cls(cls.Params(**params), step_size=0.1), seed)
            errors += flight.errors
            stds += flight.stds
            hits.append(flight.coverage())
        label = ", ".join(f"{k} {v:.3g}" for k, v in params.items() if "gps" in k)
        print(f"{name:26s} {label:34s} {math.sqrt(np.mean(np.square(errors))):6.2f} "
              f"{np.median(stds):8.2f} {np.mean(hits):8.1%}", flush=True)


if __name__ == "__main__":
    main()
