"""Hypothesis without its timing checks, on examples derived from each test: a property holds
or fails whatever the machine's load (one pytest-xdist worker per core, CI's other work) and
whatever the run, so a failure in CI is one anyone reproduces. Speed has its place in
``benchmarks/``, not in tests."""

from hypothesis import HealthCheck, settings

settings.register_profile("altfusion", deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("altfusion")
