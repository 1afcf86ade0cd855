"""Aggregation of stored runs: exact values on constructed errors, statistics on random ones."""

import numpy as np
import pytest

from altfusion.cosim.results import Results
from altfusion.montecarlo.aggregation import aggregate
from altfusion.montecarlo.source import CampaignError
from altfusion.montecarlo.storage import RunRecord, write_failure, write_manifest, write_run

TIME = np.arange(0, 10.5, 0.5)


def write_campaign(folder, errors: np.ndarray, runs: int | None = None, time=TIME):
    """A campaign whose run r records truth h = 100 + t and estimate h + errors[r]."""
    write_manifest(folder, {"format": 1, "runs": runs or len(errors), "master_seed": 0,
                            "system": {"name": "synthetic"}, "ssp": "synthetic.ssp",
                            "ssp_sha256": "0" * 64, "parameters": {},
                            "seeded_components": ["est"], "recorded": ["true.h", "est.h"],
                            "versions": {}, "created": "2026-01-01T00:00:00+00:00",
                            "sessions": [],
                            "metrics": [{"name": "h error", "estimate": "est.h",
                                         "truth": "true.h"}]})
    for index, error in enumerate(errors):
        truth = 100.0 + time
        results = Results(time, {"true.h": truth, "est.h": truth + error},
                          {"true.h": "m", "est.h": "m"})
        write_run(folder, RunRecord(index, {"est.seed": index}, results, 0.0))


def test_constant_errors_give_exact_statistics(tmp_path):
    offsets = np.array([1.0, -2.0, 3.0, 2.0])
    write_campaign(tmp_path, np.repeat(offsets[:, None], TIME.size, axis=1))
    statistics = aggregate(tmp_path)
    h = statistics.metrics[0]
    assert h.unit == "m"
    assert h.rms == pytest.approx(np.sqrt(np.mean(offsets**2)))  # sqrt(18/4)
    assert h.mean == pytest.approx(1.0)
    assert h.std == pytest.approx(np.std(offsets))  # about the overall mean, over all samples
    assert (h.max_abs, h.max_abs_run, h.max_abs_time) == (3.0, 2, 0.0)
    assert np.allclose(h.profile.rms, np.sqrt(4.5))
    assert np.allclose(h.profile.mean, 1.0)
    assert np.allclose(h.run_rms, np.abs(offsets))
    assert h.rms_ci.low <= h.rms <= h.rms_ci.high
    assert statistics.seeds == [{"est.seed": i} for i in range(4)]


def test_gaussian_errors_recover_sigma_within_the_stated_intervals(tmp_path):
    """200 runs of white errors, σ = 0.5 m, bias 0.1 m: the intervals of RMS, mean and σ
    contain the true values (fixed seed) and the per-time RMS band contains 95 % ± 10 %
    of the samples' true RMS (21 samples: a loose bound for the count)."""
    rng = np.random.default_rng(11)
    sigma, bias = 0.5, 0.1
    write_campaign(tmp_path, bias + sigma * rng.standard_normal((200, TIME.size)))
    h = aggregate(tmp_path).metrics[0]
    true_rms = np.hypot(sigma, bias)
    assert h.rms_ci.low <= true_rms <= h.rms_ci.high
    assert h.mean_ci.low <= bias <= h.mean_ci.high
    assert h.std_ci.low <= sigma <= h.std_ci.high
    assert h.rms == pytest.approx(true_rms, rel=0.03)  # 4200 samples: rel. s.e. ~1.1 %
    inside = (h.profile.rms_low <= true_rms) & (true_rms <= h.profile.rms_high)
    assert inside.mean() >= 0.85


def test_failed_and_missing_runs_are_counted_not_aggregated(tmp_path):
    write_campaign(tmp_path, np.ones((3, TIME.size)), runs=5)
    write_failure(tmp_path, 4, "component 'est': boom")
    statistics = aggregate(tmp_path)
    assert statistics.runs == [0, 1, 2]
    assert statistics.failed == {4: "component 'est': boom"}
    assert statistics.expected_runs == 5


def test_a_single_run_has_statistics_without_intervals(tmp_path):
    write_campaign(tmp_path, np.full((1, TIME.size), 2.0))
    h = aggregate(tmp_path).metrics[0]
    assert h.rms == 2.0
    assert h.rms_ci is None and h.mean_ci is None and h.std_ci is None
    assert h.profile.mean_low is None


def test_runs_on_other_output_times_are_refused(tmp_path):
    write_campaign(tmp_path, np.zeros((2, TIME.size)), runs=3)
    truth = np.zeros(3)
    write_run(tmp_path, RunRecord(2, {}, Results(np.arange(3.0), {"true.h": truth,
                                                                  "est.h": truth}), 0.0))
    with pytest.raises(CampaignError, match="run 2 has other output times"):
        aggregate(tmp_path)


def test_a_campaign_without_finished_runs_is_a_clear_error(tmp_path):
    write_campaign(tmp_path, np.zeros((0, TIME.size)), runs=3)
    with pytest.raises(CampaignError, match="holds no finished runs"):
        aggregate(tmp_path)
