"""The estimators' outputs do not depend on the processor's BLAS kernel.

numpy's OpenBLAS picks its kernels for the processor at run time (with fused multiply-adds
on Haswell and later, without on Sandy Bridge), and their products round differently: an
estimator stepped on numpy's matrix products gives other bits on another machine (before
BaselineKF, WhangGAEstimator and XuSHAEKF stepped on scalar arithmetic, 36 of the 46 cases of
tests/test_estimator_checksums.py failed under ``OPENBLAS_CORETYPE=Sandybridge``). Here the
checksum cases of every estimator run in two processes, each forced onto one of these two
kernels by ``OPENBLAS_CORETYPE``, and must give the recorded checksums in both.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
KERNELS = ("Haswell", "Sandybridge")
"""OpenBLAS core types with and without fused multiply-adds (any x86-64 processor with AVX2
runs both)."""
CASES = (("xu2016_hover15", True), ("whang2008", False), ("yang2020_baseline", True),
         ("nominal", True))
"""Checksum cases covering every estimator: Xu's system (XuSHAEKF, BaselineKF, Xu's plain
Kalman filter), Whang's paper path, BaselineKF in Yang's system and the fault suite's flight
with all seven estimators."""

WORKER = """
import hashlib, json, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
rng = np.random.default_rng(0)
A, B = rng.standard_normal((200, 4, 4)), rng.standard_normal((200, 4, 4))
products = hashlib.sha256(np.array([a.dot(b) for a, b in zip(A, B)]).tobytes()).hexdigest()
from test_estimator_checksums import checksums
cases = [(name, detection, checksums(name, detection)) for name, detection in
         json.loads(sys.argv[2])]
print(json.dumps({"products": products, "cases": cases}))
"""


def run_on_kernel(kernel: str) -> dict:
    """The worker's results in a process whose OpenBLAS runs ``kernel``."""
    environment = {**os.environ, "OPENBLAS_CORETYPE": kernel, "OPENBLAS_VERBOSE": "0"}
    output = subprocess.run([sys.executable, "-c", WORKER, str(TESTS), json.dumps(CASES)],
                            env=environment, capture_output=True, text=True, check=True)
    return json.loads(output.stdout)


def runs_haswell_kernels() -> bool:
    """True on an x86-64 processor with AVX2 and FMA (Linux): OpenBLAS forced onto its
    Haswell kernels elsewhere would stop on an illegal instruction."""
    cpuinfo = Path("/proc/cpuinfo")
    flags = cpuinfo.read_text().split() if cpuinfo.exists() else []
    return "avx2" in flags and "fma" in flags


@pytest.mark.skipif(not runs_haswell_kernels(), reason="needs an x86-64 processor with AVX2 "
                    "and FMA to run OpenBLAS's kernels with and without fused multiply-adds")
def test_every_estimator_gives_its_checksums_on_either_blas_kernel():
    from test_estimator_checksums import CHECKSUMS

    results = {kernel: run_on_kernel(kernel) for kernel in KERNELS}
    if len({result["products"] for result in results.values()}) == 1:
        pytest.skip("this numpy's BLAS gives the same products on both kernels (not an "
                    "OpenBLAS that picks its kernel by OPENBLAS_CORETYPE, or not x86-64)")
    for kernel, result in results.items():
        for name, detection, digests in result["cases"]:
            assert digests == CHECKSUMS[name, detection], (kernel, name, detection)
