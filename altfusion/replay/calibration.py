"""What a flight log says of its datums: the launch calibration of the replay tuning
(:mod:`altfusion.systems.replay`)."""

import numpy as np

from altfusion.constants import ISA_T0
from altfusion.replay.extract import FlightLog


def launch_calibration(log: FlightLog) -> dict[str, float]:
    """What the log says of its datums: Whang's H0 and T0 at the log's start (the first valid
    GPS altitude and the first baro temperature; PX4's own datum, 0 m and 288.15 K, if the log
    has no GPS fix or no air data), and ``terrain_h``, the ground's altitude in the GPS datum
    under the rangefinder: the median of GPS altitude minus rangefinder height (0 m if the log
    lacks either)."""
    gps, baro = log.stream("gps"), log.stream("baro")
    if gps is None or baro is None or not len(baro) or gps.valid is None or not gps.valid.any():
        return {"H0": 0.0, "T0": ISA_T0, "terrain_h": 0.0}
    fixed = np.flatnonzero(gps.valid)
    calibration = {"H0": float(gps.values["gps_h"][fixed[0]]),
                   "T0": float(baro.values["baro_T"][0]), "terrain_h": 0.0}
    for prefix in ("laser", "radar"):
        ranger = log.stream(prefix)
        if ranger is None or ranger.valid is None or not ranger.valid.any():
            continue
        span = (ranger.time >= gps.time[fixed[0]]) & (ranger.time <= gps.time[fixed[-1]])
        seen = ranger.valid & span
        if seen.any():
            gps_at = np.interp(ranger.time[seen], gps.time[fixed], gps.values["gps_h"][fixed])
            ground = gps_at - ranger.values[f"{prefix}_h"][seen]
            calibration["terrain_h"] = float(np.median(ground))
            break
    return calibration
