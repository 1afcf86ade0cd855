"""What ``altfusion evaluate --told`` tells the estimators in each mode, its variants and
mistakes, and how the report shows the modes: told noise / told models side by side, the
robustness of told nothing and misstated."""

import math
from pathlib import Path

import numpy as np
import pytest

from altfusion.estimators.altitude_ekf import AltitudeEKF
from altfusion.estimators.baseline import BaselineKF
from altfusion.estimators.health import Status
from altfusion.estimators.xu import XuSHAEKF
from altfusion.estimators.yang import YangFusionKF
from altfusion.evaluation.metrics import Series, run_metrics
from altfusion.evaluation.report import format_markdown, primary, side_by_side, summary_json
from altfusion.evaluation.robustness import Robustness, cell_robustness
from altfusion.evaluation.run import Cell, choose_told
from altfusion.evaluation.scenarios import (
    EstimatorInfo,
    EvaluationError,
    Scenario,
    error_parameters,
    noise_parameters,
)
from altfusion.evaluation.told import (
    DEFAULT_TOLD,
    SITE_NAMES,
    Told,
    misstate,
    split_noise,
    split_site,
    told_variants,
)
from altfusion.systems.error_models import FLAT_TERRAIN, SENSOR_ERRORS
from altfusion.systems.faults import TRUE_NOISE
from altfusion.systems.spec import SystemSpec

HAJIYEV_NOISE = {"baro_noise": 9.0, "gps_noise": 13.0, "gps_vz_noise": 0.2}


def estimator(core) -> EstimatorInfo:
    return EstimatorInfo(core.__name__, Path(f"{core.__name__}.fmu"), core,
                         frozenset(core.Params.__dataclass_fields__))


def told_in_hajiyev(core, told: Told) -> dict:
    """What ``told`` tells the estimator in hajiyev, as the paper scenario asks it."""
    info = estimator(core)
    return told.tell(noise_parameters(info, HAJIYEV_NOISE),
                     error_parameters(info, SENSOR_ERRORS["hajiyev"]))


def test_told_noise_gives_the_noise_and_no_stated_error_model():
    told = told_in_hajiyev(AltitudeEKF, Told("noise"))
    assert told == HAJIYEV_NOISE
    assert "P0_offset" not in told


def test_told_models_gives_the_noise_and_the_stated_error_models():
    told = told_in_hajiyev(AltitudeEKF, Told("models"))
    assert {k: told[k] for k in HAJIYEV_NOISE} == HAJIYEV_NOISE
    assert told["P0_offset"] == SENSOR_ERRORS["hajiyev"]["P0_offset"]
    assert told_in_hajiyev(BaselineKF, DEFAULT_TOLD)["bias_psd"] == \
        SENSOR_ERRORS["hajiyev"]["baro_bias_psd"]


def test_told_nothing_gives_nothing():
    assert told_in_hajiyev(AltitudeEKF, Told("nothing")) == {}
    assert told_in_hajiyev(BaselineKF, Told("nothing")) == {}


@pytest.mark.parametrize("factor", [0.2, 5.0])
def test_misstated_tells_every_noise_times_the_factor_and_a_variance_its_square(factor):
    sigma = told_in_hajiyev(AltitudeEKF, Told("misstated", factor))
    assert sigma == pytest.approx({k: factor * v for k, v in HAJIYEV_NOISE.items()})
    variance = told_in_hajiyev(BaselineKF, Told("misstated", factor))
    assert variance == pytest.approx({"R_baro": factor**2 * 81.0, "R_gps": factor**2 * 169.0})
    assert "bias_psd" not in variance                  # the error models are not told


def test_misstated_in_the_fault_flight_keeps_its_settings_beyond_the_noise():
    """The fault flight's settings (TRUE_NOISE) are its noise statement: the noises among
    them, Bao's user range error (σ) and worst variance too, are misstated; its flat terrain
    and AltitudeEKF's range reference are not noises."""
    bao = misstate(TRUE_NOISE["BaoDriftEstimator"], 5.0)
    assert bao["user_range_error"] == pytest.approx(
        5.0 * TRUE_NOISE["BaoDriftEstimator"]["user_range_error"])
    assert bao["R_worst"] == pytest.approx(25.0 * TRUE_NOISE["BaoDriftEstimator"]["R_worst"])
    ekf = misstate(TRUE_NOISE["AltitudeEKF"], 0.2)
    assert ekf["baro_noise"] == pytest.approx(0.2 * TRUE_NOISE["AltitudeEKF"]["baro_noise"])
    assert ekf["acc_noise"] == pytest.approx(0.2 * TRUE_NOISE["AltitudeEKF"]["acc_noise"])
    for kept in ("terrain_h", "P0_terrain", "terrain_psd", "height_ref"):
        assert ekf[kept] == TRUE_NOISE["AltitudeEKF"][kept]
    hajiyev = misstate(TRUE_NOISE["HajiyevAdaptiveEstimator"], 0.2)
    assert hajiyev["drift_psd"] == TRUE_NOISE["HajiyevAdaptiveEstimator"]["drift_psd"]


def told_in(scenario: str, core, told: Told, noise: dict) -> dict:
    """What ``told`` tells the estimator in paper scenario ``scenario``."""
    info = estimator(core)
    return told.tell(noise_parameters(info, noise),
                     error_parameters(info, SENSOR_ERRORS[scenario]))


@pytest.mark.parametrize("mode", ["noise", "nothing", "misstated"])
def test_every_mode_tells_the_terrain_and_no_sensor_error_model(mode):
    """The site (the flat terrain at 0 m the paper systems with a rangefinder fly over) is
    told in every mode; the sensor error models only in models."""
    flat = {k: SENSOR_ERRORS["yang2020"][k] for k in SITE_NAMES}
    told = told_in("yang2020", AltitudeEKF, Told(mode, 0.2 if mode == "misstated" else 1.0),
                   {"baro_noise": 20.0})
    assert {k: told[k] for k in SITE_NAMES} == flat == {"terrain_h": 0.0, "P0_terrain": 1e-8,
                                                         "terrain_psd": 0.0}
    assert set(told) - set(SITE_NAMES) <= {"baro_noise"}
    assert "P0_offset" not in told and "baro_bias_psd" not in told


@pytest.mark.parametrize("core", [YangFusionKF, XuSHAEKF])
def test_the_paper_estimators_with_a_rangefinder_assume_the_told_terrain_by_default(core):
    """Telling the site changes nothing for the paper estimators: their terrain is the flat
    ground at 0 m whatever they are told, so AltitudeEKF told it compares on the same
    knowledge."""
    for scenario in ("yang2020", "xu2016_hover15"):
        site = told_in(scenario, core, Told("nothing"), {})
        assert site == {"terrain_h": 0.0}
        assert core.Params().terrain_h == site["terrain_h"]


def test_the_fault_flights_terrain_is_told_in_every_mode_its_range_reference_in_models():
    noise, models = split_noise(TRUE_NOISE["AltitudeEKF"])
    site, errors = split_site(models)
    assert site == FLAT_TERRAIN and errors == {"height_ref": "range"}
    for told in (Told("noise"), Told("nothing"), Told("misstated", 5.0)):
        assert {k: v for k, v in told.tell(noise, models).items() if k in SITE_NAMES} == site
        assert "height_ref" not in told.tell(noise, models)
    assert Told("models").tell(noise, models)["height_ref"] == "range"


def test_the_paper_estimator_is_observed_told_per_the_mode_only_in_nothing_and_misstated():
    assert [t.observes_own for t in told_variants(["noise", "models", "nothing", "misstated"])] \
        == [False, False, True, True, True]


def test_the_variants_come_in_the_report_order_misstated_as_two():
    variants = choose_told(["misstated", "models", "noise"])
    assert [t.name for t in variants] == ["noise", "models", "misstated_x0.2", "misstated_x5"]
    assert [t.label for t in variants] == ["noise", "models", "x0.2", "x5"]
    assert choose_told(["models"]) == [DEFAULT_TOLD]


@pytest.mark.parametrize("modes, message", [
    (["models", "everything"], "unknown told modes everything; known: noise, models, nothing, "
                               "misstated"),
    (["noise", "noise"], "--told must name each told mode once"),
    ([], "--told names no told mode"),
])
def test_a_wrong_told_mode_is_refused_naming_the_known_ones(modes, message):
    with pytest.raises(EvaluationError) as error:
        choose_told(modes)
    assert str(error.value) == message


TIME = np.round(np.arange(0.0, 100.0 + 0.05, 0.1), 10)


def cell(name: str, scenario: str, error: float, h_std: float = 1.0,
         not_applicable: str = "") -> Cell:
    """A cell of two runs with a constant error ``error`` and ``h_std``."""
    if not_applicable:
        return Cell(name, scenario, not_applicable)
    ones = np.ones_like(TIME)
    runs = [Series(TIME, error * ones, h_std * ones, ones.copy(),
                   np.full(TIME.shape, int(Status.INITIALIZED))) for _ in range(2)]
    return Cell(name, scenario, runs=[run_metrics(r) for r in runs])


def results(noise: bool = True) -> dict:
    """Two estimators in two scenarios, told noise, models, nothing, x0.2 and x5: A's error
    1 m told the noise, 0.5 m told the models, 3 m told nothing (h_std 1 m: no coverage), 2 m
    misstated; B n/a in s2."""
    errors = {"noise": 1.0, "models": 0.5, "nothing": 3.0, "misstated_x0.2": 2.0,
              "misstated_x5": 2.0}
    variants = told_variants(["noise", "models", "nothing", "misstated"] if noise
                             else ["models", "nothing", "misstated"])
    return {told: {s: [cell("A", s, errors[told.name]),
                       cell("B", s, 4.0, h_std=3.0, not_applicable="no acc" if s == "s2" else "")]
                   for s in ("s1", "s2")} for told in variants}


def markdown(evaluated: dict) -> str:
    scenarios = [Scenario(s, f"{s} flight", SystemSpec(s, "", (), (), 100.0), "plant.h", {})
                 for s in ("s1", "s2")]
    return format_markdown(evaluated, ["A", "B"], scenarios, {"runs": 2})


def table(text: str, heading: str) -> list[str]:
    """The rows of the markdown table after the line starting with ``heading``."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(heading)) + 2
    end = next(i for i in range(start, len(lines)) if not lines[i].startswith("|"))
    return lines[start + 2:end]


def test_the_matrices_show_told_noise_and_told_models_side_by_side():
    text = markdown(results())
    assert table(text, "RMS error [m] of each estimator in each scenario, told noise / "
                       "models") == ["| A | 1 / 0.5 | 1 / 0.5 |", "| B | 4 / 4 | n/a / n/a |"]
    assert table(text, "Coverage, told noise / models") == [
        "| A | 100 % / 100 % | 100 % / 100 % |", "| B | 100 % / 100 % | n/a / n/a |"]
    assert "Every metric, told models" in text


def test_the_robustness_table_gives_the_rms_over_the_told_noise_rms_and_the_coverage():
    rows = table(markdown(results()), "Robustness:")
    assert rows == ["| A | nothing | x3, 0 % | x3, 0 % |", "| A | x0.2 | x2, 100 % | x2, 100 % |",
                    "| A | x5 | x2, 100 % | x2, 100 % |", "| B | nothing | x1, 100 % | n/a |",
                    "| B | x0.2 | x1, 100 % | n/a |", "| B | x5 | x1, 100 % | n/a |"]


def test_without_told_noise_the_robustness_table_gives_the_rms_in_metres():
    rows = table(markdown(results(noise=False)), "Robustness:")
    assert rows[0] == "| A | nothing | 3 m, 0 % | 3 m, 0 % |"
    assert "told noise / models" not in markdown(results(noise=False))


def test_a_cell_without_a_finite_rms_has_no_robustness_numbers():
    assert Robustness().text() == "-"
    assert cell_robustness(Cell("A", "s", "no acc"), None).text() == "n/a"
    unrun = cell_robustness(Cell("A", "s"), cell("A", "s", 1.0))
    assert math.isnan(unrun.ratio) and unrun.text() == "-"


def test_the_default_alone_reads_as_before():
    default = {DEFAULT_TOLD: results()[DEFAULT_TOLD]}
    assert side_by_side(default) == [DEFAULT_TOLD] and primary(default) == DEFAULT_TOLD
    text = markdown(default)
    assert text.startswith("RMS error [m] of each estimator in each scenario (mean over 2 "
                           "runs; in brackets: over the column's best):")
    assert table(text, "RMS error") == ["| A | 0.5 (x1) | 0.5 (x1) |",
                                        "| B | 4 (x8) | n/a |"]
    assert "Robustness" not in text and "told" not in text


def test_the_summary_has_every_variant():
    import json

    summary = json.loads(summary_json(results()))
    assert list(summary) == ["noise", "models", "nothing", "misstated_x0.2", "misstated_x5"]
    assert summary["nothing"]["s1"]["A"]["rms"]["mean"] == pytest.approx(3.0)
    assert summary["models"]["s2"]["B"] == {"not_applicable": "no acc"}
