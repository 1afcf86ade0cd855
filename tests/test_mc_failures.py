"""A failed run of a campaign is stored with its traceback and reported in one line that says
the cause (not the ``_RemoteTraceback`` header a worker's exception arrives with)."""

import math
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

from altfusion.cosim.instances import CosimError
from altfusion.montecarlo.commands import _headline
from altfusion.montecarlo.execution import _describe


def test_a_worker_exception_is_summarized_in_one_line_with_its_cause():
    with ProcessPoolExecutor(1, mp_context=get_context("spawn")) as pool:
        error = pool.submit(math.sqrt, -1.0).exception()
    message = _describe(error)
    assert _headline(message) == "ValueError: math domain error"
    assert "_RemoteTraceback" in message and 'in _process_worker' in message  # kept in full


def test_a_component_failure_keeps_its_own_first_line():
    error = CosimError("component 'plant': doStep(t = 0.0 s, h = 0.01 s) failed: ValueError: "
                       "x\nTraceback (most recent call last):\n  ...")
    assert _headline(_describe(error)) == ("component 'plant': doStep(t = 0.0 s, h = 0.01 s) "
                                           "failed: ValueError: x")
