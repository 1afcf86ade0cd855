"""A component's warnings in a run (altfusion/cosim/results.py): kept up to a bound, the rest
counted, never lost silently."""

import copy

from altfusion.cosim.results import MAX_WARNINGS, Warnings


def test_warnings_beyond_the_bound_are_counted_across_every_batch():
    """Before, each batch past the bound overwrote the last entry with that batch's count
    alone (two batches of 5 and 7 past a full list said '7 more')."""
    warnings = Warnings()
    warnings.keep(["a"] * (MAX_WARNINGS - 2))
    warnings.keep(["b"] * 5)
    warnings.keep(["c"] * 7)
    assert len(warnings) == MAX_WARNINGS
    assert warnings[-2] == "b" and warnings[-1] == "... 11 more warnings not kept"
    assert warnings.total == MAX_WARNINGS - 2 + 5 + 7
    kept = copy.copy(warnings)                  # as a run's results hold them
    assert kept.total == warnings.total and kept == warnings
    warnings.clear()
    warnings.keep(["d"])
    assert warnings == ["d"] and warnings.total == 1
