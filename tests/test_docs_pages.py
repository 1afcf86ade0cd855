"""Generated documentation pages: the FMU reference plots carry units on their axes and an
estimator's error with its ±2 h_std band; docs/replay.md's table is the build's."""

from pathlib import Path

import numpy as np
import pytest

from altfusion.cosim.results import Results
from altfusion.docs import REPLAY_SUMMARY, ReferenceRun, reference_figure, replace_generated
from altfusion.estimators.registry import ESTIMATOR_CLASSES

DOCS = Path(__file__).resolve().parents[1] / "docs"
TIME = np.linspace(0.0, 100.0, 201)


def results() -> Results:
    """A 1500 m flight and an estimate 0.3 m off it, claiming h_std 0.2 m."""
    h = 15.0 * TIME
    return Results(TIME, {"plant.h": h, "estimator.h_est": h + 0.3,
                          "estimator.h_std": np.full_like(TIME, 0.2),
                          "estimator.status": np.ones_like(TIME)},
                   {"plant.h": "m", "estimator.h_est": "m", "estimator.h_std": "m",
                    "estimator.status": ""})


def test_every_axis_of_a_reference_plot_names_its_unit():
    run = ReferenceRun("s", "estimator", (("h_est", "plant.h"), ("h_std",), ("status",)))
    labels = [ax.get_ylabel() for ax in reference_figure(run, results()).axes]
    assert labels == ["h_est [m]", "h_std [m]", "status [-]", "error [m]"]


def test_an_estimators_reference_plot_shows_its_error_within_its_band():
    run = ReferenceRun("s", "estimator", (("h_est", "plant.h"), ("h_std",)))
    error = reference_figure(run, results()).axes[-1]
    lines = {line.get_label(): line for line in error.get_lines()}
    assert np.allclose(lines["estimator.h_est - plant.h [m]"].get_ydata(), 0.3)
    assert [c.get_label() for c in error.collections] == ["±2 estimator.h_std [m]"]
    low, high = error.get_ylim()
    assert low > -1.0 and high < 1.0                 # decimetres, not the 0-1500 m flight


def test_a_plot_without_an_estimate_gets_no_error_panel():
    run = ReferenceRun("s", "plant", (("plant.h",),))
    assert len(reference_figure(run, results()).axes) == 1


def test_the_generated_part_of_a_page_is_replaced_between_its_markers():
    begin, end = REPLAY_SUMMARY
    page = f"intro\n{begin}\nold table\n{end}\noutro\n"
    assert replace_generated(page, REPLAY_SUMMARY, "new table\n") == \
        f"intro\n{begin}\nnew table\n{end}\noutro\n"
    with pytest.raises(ValueError, match="lacks the markers"):
        replace_generated("no markers", REPLAY_SUMMARY, "x")


def test_the_replay_page_table_is_the_builds_with_every_catalog_estimator():
    page = (DOCS / "replay.md").read_text()
    table = page.split(REPLAY_SUMMARY[0])[1].split(REPLAY_SUMMARY[1])[0]
    names = [line.split(" | ")[0].lstrip("| ") for line in table.strip().splitlines()[2:]]
    assert names == ["PX4 EKF2 (reference)", *ESTIMATOR_CLASSES]
