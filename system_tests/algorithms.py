"""The two ways the paper reproductions run (``reproduce_cli`` in conftest.py)."""

import pytest

PAPER_ALGORITHM = "paper_algorithm"
"""Every estimator with ``fault_detection`` false (``altfusion reproduce --paper-algorithm``)."""

ALGORITHMS = ("fault_detection", PAPER_ALGORITHM)
"""The two ways every reproduction runs: its estimators as they ship (``fault_detection``
true, the shared health machinery's resets, isolation and bias states) and as their papers
give them (``altfusion reproduce --paper-algorithm``). Issue 15: every reproduction stays
within its bounds either way."""

DEFAULT = ALGORITHMS[:1]
"""A reproduction fixture's own parameters: the default algorithm only."""


def either_way(fixture: str) -> pytest.MarkDecorator:
    """Run a test on reproduction fixture ``fixture`` in each of :data:`ALGORITHMS`. The
    fixture is declared with ``params=DEFAULT``, so that the tests without this mark share the
    default's one module-scoped run with the marked ones (pytest caches a fixture by its
    parameter's value)."""
    return pytest.mark.parametrize(fixture, ALGORITHMS, indirect=True)
