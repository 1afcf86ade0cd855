"""The evaluation's page decides at a glance: heat maps of the RMS (in ratios to the
column's best) and of the coverage with the best marked and every cell linked to its plot;
per-cell plots of a readable size on one scale per scenario with every mark in the legend;
max |e| and recovery after the start-up; the run count beside every spread; the RMS over
runs as ``altfusion report`` computes it."""

import math
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from altfusion.estimators.health import Status
from altfusion.evaluation.metrics import (
    RECOVERY_WINDOW,
    STARTUP_TIME,
    Fault,
    Series,
    max_abs,
    run_metrics,
    summarize,
    time_to_recover,
)
from altfusion.evaluation.report import (
    PLOT_DPI,
    cell_figure,
    cell_row,
    figure_margins,
    scenario_scale,
    write_html,
)
from altfusion.evaluation.run import Cell
from altfusion.evaluation.scenarios import Scenario
from altfusion.evaluation.told import DEFAULT_TOLD
from altfusion.scores import pooled_rms
from altfusion.systems.spec import SystemSpec

DT = 0.1
TIME = np.round(np.arange(0.0, 200.0 + DT / 2, DT), 10)
INITIALIZED = int(Status.INITIALIZED)


def series(error, status=INITIALIZED) -> Series:
    ones = np.ones_like(TIME)
    return Series(TIME, np.asarray(error, dtype=float) * ones, ones.copy(), ones.copy(),
                  np.broadcast_to(np.asarray(status), TIME.shape).astype(np.int64))


def test_max_abs_ignores_the_start_up():
    """A 9.21 m initial transient (seconds 1-3 after the first fused sample at 1 s) is the
    start-up; the 2 m at 150 s is what the estimator does afterwards."""
    error = np.where((TIME >= 1.0) & (TIME < 3.0), 9.21, 0.5)
    error[TIME == 150.0] = -2.0
    s = series(error, status=np.where(TIME >= 1.0, INITIALIZED, 0))
    assert s.startup_end == pytest.approx(1.0 + STARTUP_TIME)
    assert max_abs(s) == 2.0


def test_recovery_of_a_fault_from_the_start_counts_from_the_end_of_the_start_up():
    """A fault acting from 0 s: the start-up transient is no failure to recover; an error
    beyond 3x the nominal RMS until 50 s is (its trailing 2 s window clean from 52 s), and
    recovery is counted from the end of the start-up."""
    fault = Fault(0.0)
    startup_only = np.where(TIME < 10.0, 100.0, 0.5)
    assert time_to_recover(series(startup_only), fault, 1.0) == 0.0
    late = np.where(TIME < 50.0, 100.0, 0.5)
    assert time_to_recover(series(late), fault, 1.0) == pytest.approx(
        50.0 + RECOVERY_WINDOW - STARTUP_TIME, abs=DT + 1e-9)


def test_every_spread_carries_its_run_count():
    assert summarize([10.0, 62.4]).format() == "36.2 ± 37.1 (n=2)"
    assert summarize([1.0, math.inf, 3.0]).format(unit="s") == "2 ± 1.41 s (n=2 of 3)"
    assert summarize([4.0]).format() == "4 (n=1)"


def cell(name: str, scenario: str, rms_values: list[float], startup: float = 0.0) -> Cell:
    """A cell whose runs have constant errors of the given RMS (h_std 1 m)."""
    runs = [series(value) for value in rms_values]
    c = Cell(name, scenario, runs=[run_metrics(r) for r in runs], time=TIME,
             errors=np.vstack([r.error for r in runs]),
             h_std=np.vstack([r.h_std for r in runs]), startup_end=startup)
    return c


def scenario(name: str, fault: Fault | None = None) -> Scenario:
    return Scenario(name, f"{name} flight", SystemSpec(name, "", (), (), 200.0), "plant.h", {},
                    fault=fault)


def test_the_rms_of_a_cell_is_the_rms_over_runs_as_the_campaign_report_computes_it():
    """Two runs of RMS 10 and 62.4: 36.2 as a mean of RMS, 44.7 as the RMS over runs."""
    c = cell("A", "s", [10.0, 62.4])
    assert c.rms == pytest.approx(pooled_rms(np.array([100.0, 62.4**2])))
    assert c.rms == pytest.approx(math.sqrt((100.0 + 62.4**2) / 2))
    assert cell_row(c)[3] == f"{c.rms:.3g} ± 37.1 (n=2)"


@pytest.fixture
def page(tmp_path: Path) -> str:
    cells = {"s1": [cell("A", "s1", [1.0, 1.0]), cell("B", "s1", [30.0, 30.0]),
                    Cell("C", "s1", "no acc")],
             "s2": [cell("A", "s2", [10.0, 10.0]), cell("B", "s2", [2.0, 2.0]),
                    cell("C", "s2", [4.0, 4.0])]}
    path = write_html(tmp_path / "evaluation.html", {DEFAULT_TOLD: cells}, ["A", "B", "C"],
                      [scenario("s1"), scenario("s2", Fault(100.0, ("baro",), 40.0))],
                      {"runs": 2, "master_seed": 0, "backend": "core"})
    return path.read_text()


def test_the_rms_heat_map_is_coloured_in_ratios_with_the_best_per_column_marked(page):
    assert "log10" not in page
    key = re.search(r'<p class="key">colour: RMS over the column.*?</p>', page).group(0)
    assert re.findall(r">(x[0-9.]+)", key) == ["x1", "x1.5", "x3", "x10", "x30", "x100"]
    best = re.findall(r'<td class="best"[^>]*><a href="#(cell-[^"]+)">([^<]+)</a>', page)
    # RMS heat map: A best in s1, B in s2; coverage (all 100 % here: ties): the first.
    assert best[:2] == [("cell-s1-A", "1 ★"), ("cell-s2-B", "2 ★")]


def test_every_heat_map_cell_links_to_its_plot_and_every_column_to_its_section(page):
    targets = set(re.findall(r'<a href="#([^"]+)"', page))
    ids = set(re.findall(r' id="([^"]+)"', page))
    assert {"cell-s1-A", "cell-s1-B", "cell-s2-A", "cell-s2-B", "cell-s2-C", "s1",
            "s2"} <= targets
    assert targets <= ids
    assert "<h2>Coverage</h2>" in page and "100 %" in page


def test_the_heat_maps_text_is_at_least_11_px():
    from altfusion.evaluation.report import PAGE_STYLE

    sizes = re.findall(r"\.heat td,\.heat th\{font-size:(\d+)px", PAGE_STYLE)
    assert sizes and int(sizes[0]) >= 11


def test_a_cell_plot_is_readable_and_names_every_mark_in_its_legend():
    fault = Fault(100.0, ("baro",), 40.0)
    c = cell("A", "s", [1.0, 2.0], startup=STARTUP_TIME)
    fig = cell_figure(c, scenario("s", fault), scenario_scale([c]))
    width, height = (fig.get_size_inches() * PLOT_DPI).round()
    assert width >= 500 and height >= 280
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels == ["each run (n=2)", "RMS over runs", "2 h_std (mean over runs)",
                      "start-up (no max |e|, recover)", "fault transient (no coverage)",
                      "fault start 100 s"]
    fonts = [t.get_fontsize() for t in (fig.axes[0].xaxis.label, fig.axes[0].title)]
    assert min(fonts) * PLOT_DPI / 72 >= 11                     # px


def test_every_plot_of_a_scenario_shares_one_log_y_scale():
    """Errors of 0.4 m and 500 m (constant: their trailing RMS too) on one axis."""
    cells = [cell("A", "s", [0.4, 0.4]), cell("B", "s", [500.0, 500.0])]
    scale = scenario_scale(cells)
    axes = [cell_figure(c, scenario("s"), scale).axes[0] for c in cells]
    assert {ax.get_ylim() for ax in axes} == {scale}
    assert {ax.get_yscale() for ax in axes} == {"log"}
    assert scale == pytest.approx((0.2, 1000.0))


def test_every_plot_of_a_scenario_has_the_tight_layout_of_its_first():
    """The page lays a scenario's plots out once (the first cell's tight layout, reused):
    right only if each cell's own tight layout is the same, as here for an estimator 1000x
    worse than the first and a title twice as long."""
    fault = Fault(100.0, ("baro",), 40.0)
    cells = [cell("A", "s", [0.4, 0.4]), cell("AltitudeEKF_long_name", "s", [400.0, 500.0])]
    scale = scenario_scale(cells)
    margins = [figure_margins(cell_figure(c, scenario("s", fault), scale)) for c in cells]
    assert margins[0] == margins[1]
    reused = cell_figure(cells[1], scenario("s", fault), scale, margins[0])
    assert figure_margins(reused) == margins[0]


def test_the_page_images_are_pngs_at_the_plot_size(page):
    import base64
    import io

    data = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    assert len(data) == 5                                       # C is n/a in s1
    sizes = {Image.open(io.BytesIO(base64.b64decode(d))).size for d in data}
    assert sizes == {(530, 400)}
