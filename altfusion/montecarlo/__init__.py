"""Monte Carlo campaigns of co-simulated systems: seeded runs in parallel worker processes or on
a Dask cluster, streamed to disk, aggregated into error statistics and reported.

This package sits on top of :mod:`altfusion.cosim`; the core numerics know nothing of it.
"""
