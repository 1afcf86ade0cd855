"""Paper reproduction of yang2020 (``altfusion reproduce yang2020``), with a reduced Monte Carlo
(the first ``RUNS`` runs of master seed 0: the first runs of the full reproduction), and the
reference CSVs of its scenarios.

Each statistical assertion states its tolerance and where it comes from; the numbers of the
full reproduction are in the README ("Paper reproduction: yang2020 (Yang et al.)").
"""

from pathlib import Path

import numpy as np
import pytest
from algorithms import DEFAULT, either_way

from altfusion.montecarlo.statistics import rms_chi2_bounds
from altfusion.montecarlo.storage import read_run
from altfusion.reproduce import yang2020
from altfusion.reproduce.common import reference_differences

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
RUNS = 4


@pytest.fixture(scope="module", params=DEFAULT)
def yang(reproduce_cli, tmp_path_factory, request):
    """``altfusion reproduce yang2020 -n RUNS`` in a subprocess: (out, stdout, analysis)."""
    out = tmp_path_factory.mktemp("yang2020")
    return out, reproduce_cli("yang2020", RUNS, out, request.param), yang2020.analyse(out)


def test_yang_reproduction_writes_fig2_and_the_tables(yang):
    out, stdout, analysis = yang
    assert analysis.runs == list(range(RUNS))
    for name in ("yang2020_fig2.png", "yang2020_errors.png", "yang2020.md"):
        assert (out / name).stat().st_size > 1000
        assert f"wrote {out / name}" in stdout
    assert "| fusion filter beats every sensor (Section 4.2, counts of runs) |" in stdout
    assert (out / "yang2020.md").read_text() in stdout


@either_way("yang")
def test_yang_weighted_fusion_sigma_matches_its_theory(yang):
    """Section 3.2: 1/σ_Y² = Σ 1/σ_i² gives σ_Y = 8.571 m for 30 / 20 / 10 m. YangFusionKF
    reports exactly that at every fusion instant (all three sensors live). Its errors there
    are white and Gaussian: n·RMS²/σ² is χ²(n) over the n = RUNS × 2100 fusions, so σ_Y must
    lie in the 99 % chi-square interval of the measured RMS (±2.8 % for 4 runs). The same
    holds for each sensor at its own samples, with its Section 4.2 σ."""
    _, _, a = yang
    fused_sigma = yang2020.FUSED_SIGMA
    assert fused_sigma == pytest.approx((1 / 30**2 + 1 / 20**2 + 1 / 10**2) ** -0.5)
    assert fused_sigma == pytest.approx(8.5714, abs=1e-4)  # 8.571428... to 4 decimals
    # the FMU computes the same formula: rounding only (a few ε = 2.2e-16 relative)
    np.testing.assert_allclose(a.fused_std, yang2020.FUSED_SIGMA, rtol=1e-12)
    expected = {**yang2020.SENSOR_SIGMAS, "weighted fusion": yang2020.FUSED_SIGMA}
    for way, sigma in expected.items():
        errors = a.errors[way][1]
        assert errors.shape[1] == (4200 if way in ("GPS", "baro") else 2100), way
        low, high = rms_chi2_bounds(np.mean(errors**2), errors.size, 0.99)
        assert low < sigma < high, (way, low, high)


@either_way("yang")
def test_yang_kalman_filter_beats_every_sensor_and_the_fusion_in_every_run(yang):
    """Section 4.2's "499 / 491 / 388 times better than GPS / baro / radio altimeter", read as
    counts of runs (docs/papers.md): here the filter's σ of eq. (15) is below every sensor's and
    below the weighted fusion's in every run (all 125 runs of the full reproduction). By a
    wide margin: the 95 % interval of the filter's RMS (each run one sample, t with 3
    degrees of freedom) lies below σ_Y / 4 = 2.14 m (125 runs: 0.86 [0.76, 0.95] m, a
    factor of 9.9)."""
    _, _, a = yang
    for way in (*yang2020.SENSORS, "weighted fusion"):
        assert a.beats("YangFusionKF", way) == RUNS, way
    assert a.rms("YangFusionKF").interval.high < yang2020.FUSED_SIGMA / 4


@either_way("yang")
def test_yang_baseline_kf_runs_in_the_scenario_and_loses_to_the_paper_s_filter(yang):
    """BaselineKF (baro + GPS, no radio altimeter, no IMU) flies the same loop on the same
    sensor noise (paired runs): YangFusionKF's σ of eq. (15) is below BaselineKF's in every
    run (125 of 125 in the full reproduction: 0.86 m against 12.6 m)."""
    _, stdout, a = yang
    print(f"BaselineKF: RMS {a.rms('BaselineKF').text(3)} m, tracking error "
          f"{a.tracking['BaselineKF'].text(3)} m")
    assert np.all(np.isfinite(a.sigmas["BaselineKF"]))
    assert a.beats("YangFusionKF", "BaselineKF") == RUNS
    assert "| BaselineKF (baro + GPS) |" in stdout


@pytest.mark.parametrize("reference", yang2020.REFERENCES, ids=lambda r: r.system)
def test_yang_campaign_run_0_is_the_reference(yang, reference):
    """Run 0 of master seed 0 of each scenario equals its reference CSV
    (``python -m altfusion.reproduce.common yang2020``) to 1e-9 relative; the campaigns'
    run 0 is that run, so the reduced Monte Carlo above is the full reproduction's start."""
    out, _, _ = yang
    campaign = {c.system: c.folder for c in yang2020.CAMPAIGNS}[reference.system]
    run = read_run(out / campaign, 0).results
    assert reference_differences(reference.sampled(run), reference.stored(ROOT)) == []
