"""The finiteness test the compiled modules make on every sample value, as a native call.

mypyc compiles ``math.isinf`` and ``math.isnan`` on a float to C tests, but not
``math.isfinite``: that one is looked up on the module and called through the interpreter at
every use (about 300 instructions, a float boxed for it). Compiled
(:data:`altfusion.compiled.COMPILED`), :func:`finite` is two C tests.
"""

import math


def finite(value: float) -> bool:
    """``math.isfinite(value)``: neither infinite nor NaN."""
    return not (math.isinf(value) or math.isnan(value))
