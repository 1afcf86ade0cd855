"""Drives an estimator core the way the sensor FMUs do: held samples, counts, time stamps.

The one stream feeder of the unit tests (estimator cores without FMI).
"""


class StreamFeeder:
    """``step(baro={"baro_h": ...}, gps=None, inputs={"wind_speed": ...})`` delivers one new
    sample of each stream given (count + 1, time stamp = the end of the step unless the sample
    gives its own), sets the extra inputs, and advances the estimator by one step.

    Like a system that connects only the inputs an estimator declares, values the estimator
    has no attribute for (``baro_T`` for BaselineKF) are not delivered."""

    def __init__(self, estimator):
        self.estimator = estimator
        self.counts: dict[str, int] = {}
        self.n = 0

    def _deliver(self, name: str, value) -> None:
        if hasattr(self.estimator, name):
            setattr(self.estimator, name, value)

    def step(self, inputs: dict[str, float] | None = None, **samples) -> None:
        e = self.estimator
        t_end = e.clock.time(self.n + 1)
        for name, value in (inputs or {}).items():
            self._deliver(name, value)
        for prefix, values in samples.items():
            if values is None:
                continue
            self.counts[prefix] = self.counts.get(prefix, 0) + 1
            for name, value in values.items():
                self._deliver(name, value)
            self._deliver(f"{prefix}_count", self.counts[prefix])
            if f"{prefix}_time" not in values:
                self._deliver(f"{prefix}_time", t_end)
        e.do_step(e.clock.time(self.n), e.dt)
        self.n += 1
