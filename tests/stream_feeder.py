"""Drives an estimator core the way the sensor FMUs do: held samples, counts, time stamps."""


class StreamFeeder:
    """``step(baro={"baro_h": ...}, gps=None, inputs={"wind_speed": ...})`` delivers one new
    sample of each stream given (count + 1, time stamp = the end of the step unless the sample
    gives its own), sets the extra inputs, and advances the estimator by one step."""

    def __init__(self, estimator):
        self.estimator = estimator
        self.counts: dict[str, int] = {}
        self.n = 0

    def step(self, inputs: dict[str, float] | None = None, **samples) -> None:
        e = self.estimator
        t_end = e.clock.time(self.n + 1)
        for name, value in (inputs or {}).items():
            setattr(e, name, value)
        for prefix, values in samples.items():
            if values is None:
                continue
            self.counts[prefix] = self.counts.get(prefix, 0) + 1
            for name, value in values.items():
                setattr(e, name, value)
            setattr(e, f"{prefix}_count", self.counts[prefix])
            if hasattr(e, f"{prefix}_time") and f"{prefix}_time" not in values:
                setattr(e, f"{prefix}_time", t_end)
        e.do_step(e.clock.time(self.n), e.dt)
        self.n += 1
