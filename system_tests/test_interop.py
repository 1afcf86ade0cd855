"""Our FMUs and SSP systems in third-party engines: libcosim, ECOS, an FMU container.

Third-party runs happen outside the test process, one Python process per engine running every
system the selected tests need one after another (engines unload FMU libraries; the native
shim makes a process survive that, as test_engines_all_systems.py shows); a run that fails
there is repeated alone in a fresh process. Our runner runs in the test process. The
reference for the engines is our runner
with ``master="jacobi"``: libcosim and ECOS are Jacobi masters, and running the same FMU code
on the same inputs they must agree with it bit for bit. Our default ordered stepping differs
from Jacobi by derived amounts, asserted below.

Every catalog system runs in every engine (``ENGINE_SYSTEMS``, its first
``ENGINE_RUN_SECONDS``, or ``SHORT_ENGINE_RUNS``). To check a system's ordered/Jacobi
difference too, give its control loop's extra delay in ``JACOBI_LOOP_DELAY``; to pack one of
its subsystems into a container, add the members to ``CONTAINER_SUBSYSTEMS``.
"""

import json
import os
import subprocess
import sys
import zipfile
from dataclasses import replace
from pathlib import Path

import control
import numpy as np
import pytest

import altfusion.interop  # noqa: E402, F401  (loads the engines' native libraries first)

pytest.importorskip("libcosimpy", reason="the interop extra is not installed")
pytest.importorskip("ecospy", reason="the interop extra is not installed")
pytest.importorskip("fmu_manipulation_toolbox", reason="the interop extra is not installed")

from altfusion.constants import G0, R_AIR  # noqa: E402
from altfusion.cosim import simulate, write_ssp  # noqa: E402
from altfusion.cosim.results import Results  # noqa: E402
from altfusion.cosim.runner import MASTERS  # noqa: E402
from altfusion.interop.__main__ import run_engine  # noqa: E402
from altfusion.interop.compliance import fmu_problems, ssp_problems  # noqa: E402
from altfusion.interop.container import (  # noqa: E402
    build_container,
    input_table,
    simulate_in_subprocess,
)
from altfusion.interop.delays import jacobi_sensor_delays  # noqa: E402
from altfusion.interop.engines import (  # noqa: E402
    EngineError,
    ecos_divergent_components,
    run_in_subprocess,
)
from altfusion.interop.osp import OSP_FILE, write_osp  # noqa: E402
from altfusion.interop.proxy import python_environment  # noqa: E402
from altfusion.physics.barometric import height_from_pressure, pressure_at  # noqa: E402
from altfusion.physics.profiles import make_profile  # noqa: E402
from altfusion.sensors.air_data import AirDataParams  # noqa: E402
from altfusion.systems import SYSTEMS, build_system  # noqa: E402
from altfusion.systems.plant import plant_components, plant_connections  # noqa: E402
from altfusion.systems.spec import ComponentSpec, Connection, SystemSpec  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
sys.path.insert(0, str(ROOT))
import build_fmu as builder  # noqa: E402

ENGINE_SYSTEMS = sorted(SYSTEMS)
"""Every catalog system (every models/*.ssp) runs in every engine."""

ENGINE_RUN_SECONDS = 120.0
"""Simulated time per engine run (a system's full length when shorter), to bound CI time."""

SHORT_ENGINE_RUNS = {
    **{name: 30.0 for name in ENGINE_SYSTEMS if name.startswith("xu2016_")},
    **{name: 40.0 for name in ("fault_flight", "fault_flight_baro_step",
                               "fault_demo_altitude_ekf", "yang2020_altitude_ekf",
                               "yang2020_baseline", "sensors_yang2020")},
    **{name: 20.0 for name in ("replay_auterion", "replay_px4_sitl")},
}
"""Shorter engine runs, s, for systems whose FMUs, rates and wiring another system's full
run already covers, to bound CI time. The four xu2016 scenarios share their FMUs and wiring
(the heaviest systems: ten FMUs at 0.01 s) and differ only in the profile and the wind; 30 s
covers the take-off, the laser's range and the first switch of the height source. The fault
flight and its baro_step variant (the fault starts at 130 s, after any engine run's end), seed
003's loop on AltitudeEKF or BaselineKF and the fault demonstration on AltitudeEKF (``yang2020``
and ``fault_demo_yang`` run their 120 s: the same loop and fault component on YangFusionKF,
through the GNSS outage from 100 s) and yang2020's sensors alone: 40 s covers every sensor
rate, the take-off and each estimator's start. The two log replays (seven estimators at
0.01 s, the costliest steps): 20 s covers every logged sensor's rate (the Auterion log's
first 29 baro, 65 GNSS and 136 laser samples) and each estimator's start. The whole-system
containers run as long as the system's engine runs."""


def engine_run_seconds(system: str) -> float:
    """Simulated time of the system's engine runs."""
    return min(build_system(system).stop_time,
               SHORT_ENGINE_RUNS.get(system, ENGINE_RUN_SECONDS))

JACOBI_LOOP_DELAY = {"plant_yang2020": 1, "whang2008": 1}
"""Base steps of delay a Jacobi master adds around the system's control loop, for loops closed
on the noise-free truth (plant -> controller: one feedthrough connection). ``yang2020`` flies
on its estimate through sensors stepped at up to 0.2 s: its path delays and bounds are derived
in ``test_yang2020_jacobi_sensors_keep_their_errors_and_the_loop_leads``."""

CONTAINER_SUBSYSTEMS = {"plant_yang2020": [("atmosphere", "controller")],
                        "whang2008": [("air_data", "estimator")]}
"""Subsystems packed into one container FMU and checked against the multi-FMU run."""

SINGLE_RATE_SYSTEMS = [name for name in ENGINE_SYSTEMS
                       if len({c.step_size for c in build_system(name).components}) == 1]
"""Catalog systems whose components share one step: each fits in one container FMU."""

# ------------------------------------------------------------------------------ compliance


def test_every_fmu_passes_fmpy_and_the_toolbox_fmi2_checker(fmus):
    assert fmus
    for path in fmus.values():
        assert fmu_problems(path) == [], path.name


def test_the_fmu_checker_reports_a_broken_model_description(fmus, tmp_path):
    """A continuous parameter is forbidden by FMI 2.0 (§2.2.7): both checkers must say so."""
    broken = tmp_path / "Broken.fmu"
    with zipfile.ZipFile(fmus["VerticalDynamics"]) as source, \
            zipfile.ZipFile(broken, "w") as target:
        for item in source.infolist():
            data = source.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = data.replace(b'causality="parameter" variability="fixed"',
                                    b'causality="parameter" variability="continuous"', 1)
            target.writestr(item, data)
    problems = fmu_problems(broken)
    assert any(p.startswith("fmu-manipulation-toolbox") for p in problems), problems


def test_every_ssp_passes_the_ssp_and_osp_checks(ssp_files):
    assert set(ssp_files) == set(SYSTEMS)
    for path in ssp_files.values():
        assert ssp_problems(path) == [], path.name


def _edited_ssp(path: Path, target: Path, old: bytes, new: bytes) -> Path:
    """A copy of ``path`` with ``old`` replaced in each of its descriptions that holds it."""
    edited = []
    with zipfile.ZipFile(path) as source, zipfile.ZipFile(target, "w") as copy:
        for item in source.infolist():
            data = source.read(item.filename)
            if item.filename.endswith(".ssd") and old in data:
                data = data.replace(old, new)
                edited.append(item.filename)
            copy.writestr(item, data)
    assert edited, old
    return target


@pytest.mark.parametrize(("old", "new", "problem"), [
    (b'baseStepSize="0.01"', b'', "no positive osp:FixedStepAlgorithm baseStepSize"),
    (b'<osp:StepSizeHint value="0.01" />', b'<osp:StepSizeHint value="0.015" />',
     "is not a multiple of the base step"),
    (b'<ssv:Real value="1.5" />', b'<ssv:Real value="heavy" />', "ParameterSet parameters"),
    (b'<ssv:Parameter name="mass">', b'<ssv:Parameter name="weight">', "no parameter weight"),
    (b'source="resources/Atmosphere.fmu"', b'source="resources/Air.fmu"', "not in the archive"),
])
def test_the_ssp_checks_report_what_breaks_an_engine(ssp_files, tmp_path, old, new, problem):
    broken = _edited_ssp(ssp_files["plant_yang2020"], tmp_path / "broken.ssp", old, new)
    assert any(problem in p for p in ssp_problems(broken)), ssp_problems(broken)


def test_an_osp_folder_is_exported_next_to_every_ssp(ssp_files):
    for name in ssp_files:
        folder = MODELS / name
        assert (folder / OSP_FILE).is_file(), name
        for component in build_system(name).components:
            assert (folder / f"{component.fmu}.fmu").is_file()


# ------------------------------------------------------------------------------ engines


OUR_ENGINES = ("altfusion", "altfusion-jacobi")
"""Our runner's engines: run in the test process (``run_engine``, as the engines' entry point
runs them; the CSV round trip of the others is exact, ``repr`` of every float)."""

ENGINE_BATCH = """
import atexit, json, sys, traceback
from pathlib import Path
from altfusion.cosim.instances import release_mapped_pythonfmu_state
from altfusion.interop.__main__ import run_engine

atexit.register(release_mapped_pythonfmu_state)
for job in json.loads(sys.argv[1]):
    try:
        run_engine(job["engine"], Path(job["ssp"]), job["stop"], Path(job["osp"])).to_csv(
            Path(job["csv"]))
    except Exception:
        Path(job["csv"] + ".error").write_text(traceback.format_exc())
"""
"""One third-party engine's runs of several systems, one after another in one process (what
test_engines_all_systems.py shows a process survives), each written to its CSV or, when it
raises, its error to ``<csv>.error``."""


def _module_systems(request) -> list[str]:
    """The catalog systems this module's collected tests run in the engines."""
    return sorted({item.callspec.params["system"] for item in request.session.items
                   if item.module is request.module and hasattr(item, "callspec")
                   and item.callspec.params.get("system") in ENGINE_SYSTEMS})


@pytest.fixture(scope="module")
def engine_runs(ssp_files, tmp_path_factory, request):
    """Every engine's run of every system in ENGINE_SYSTEMS, by (system, engine). A
    third-party engine's first run also runs the other systems this module's tests ask of
    it, in one process (ENGINE_BATCH); a run that raised there, or that a dying process
    left undone, is repeated alone in a fresh process (``run_in_subprocess``), whose error
    the test then sees."""
    cache: dict[tuple[str, str], object] = {}
    folder = tmp_path_factory.mktemp("engine_runs")

    def batch(first: str, engine: str) -> None:
        systems = [first, *(s for s in _module_systems(request)
                            if s != first and (s, engine) not in cache)]
        jobs = [{"engine": engine, "ssp": str(ssp_files[s]), "stop": engine_run_seconds(s),
                 "osp": str(MODELS / s), "csv": str(folder / f"{s}.{engine}.csv")}
                for s in systems]
        subprocess.run([sys.executable, "-c", ENGINE_BATCH, json.dumps(jobs)],
                       capture_output=True, text=True, timeout=900 * len(jobs), cwd=ROOT)
        for system, job in zip(systems, jobs, strict=True):
            if Path(job["csv"]).is_file():
                cache[system, engine] = Results.from_csv(Path(job["csv"]))

    def get(system: str, engine: str):
        if (system, engine) not in cache:
            stop = engine_run_seconds(system)
            if engine in OUR_ENGINES:
                cache[system, engine] = run_engine(engine, ssp_files[system], stop)
            else:
                batch(system, engine)
        if (system, engine) not in cache:
            cache[system, engine] = run_in_subprocess(engine, ssp_files[system], stop,
                                                      osp=MODELS / system)
        return cache[system, engine]
    return get


def _assert_identical(results, reference, columns=None, rows=slice(None), label=""):
    """Bit-identical signals; time stamps equal to 1 ns (fmpy computes n·h, we n/(1/h)).

    libcosim has no t = 0 value of a Boolean output of a component at the base step (see
    ``engines.run_libcosim``): such a column may start with NaN, and only there."""
    assert np.allclose(results.time[rows], reference.time[rows], rtol=0, atol=1e-9), label
    for name in columns or reference.columns:
        engine, ours = results[name][rows].copy(), reference[name][rows]
        boolean = np.isin(ours, (0.0, 1.0)).all()
        if label.startswith("libcosim") and rows == slice(None) and boolean \
                and np.isnan(engine[0]):
            engine[0] = ours[0]
        different = np.flatnonzero(engine != ours)
        assert different.size == 0, (
            f"{label} {name}: first difference at t = {reference.time[rows][different[0]]} s: "
            f"{engine[different[0]]!r} != {ours[different[0]]!r}")


@pytest.mark.parametrize("system", ENGINE_SYSTEMS)
@pytest.mark.parametrize("engine", ["libcosim", "libcosim-osp"])
def test_libcosim_reproduces_the_jacobi_reference_bit_for_bit(engine_runs, system, engine):
    """libcosim's fixed-step algorithm (SSP or exported OSP folder) steps every component at
    its own rate with every input latched at the start of the component's step, and observes
    outputs when a step completes: exactly ``master="jacobi"``."""
    _assert_identical(engine_runs(system, engine), engine_runs(system, "altfusion-jacobi"),
                      label=engine)


def test_libcosim_with_a_stop_time_within_one_output_interval_records_t_0(ssp_files, tmp_path):
    """A stop time shorter than one output interval records the t = 0 row only, in libcosim
    as in our runner (libcosim was asked for step(-1), which never returns)."""
    rows = {}
    for engine in ("libcosim", "altfusion"):
        csv = tmp_path / f"{engine}.csv"
        done = subprocess.run([sys.executable, "-m", "altfusion.interop", "run", "--engine",
                               engine, "--stop", "0.02", "--csv", str(csv),
                               str(ssp_files["plant_yang2020"])],
                              capture_output=True, text=True, timeout=120, cwd=ROOT)
        assert done.returncode == 0, done.stderr[-2000:]
        rows[engine] = Results.from_csv(csv)
    assert len(rows["libcosim"].time) == 1
    _assert_identical(rows["libcosim"], rows["altfusion"], label="libcosim")


ENGINE_ACCURACY_RATIO = 1.5
"""Largest ratio between two engines' RMS statistics of a column that does not come out bit
for bit (issue 14: the same accuracy, 1.5x at most). Measured on the divergent systems'
engine runs, ECOS over Jacobi: estimates 0.95-1.12 (yang2020 1.64 / 1.46 m), tracking 1.12."""

TRUTH_OF_SUFFIX = {"_h": "plant.h", "h_est": "plant.h", "h_fused": "plant.h",
                   "h_ref": "plant.h", "vz": "plant.vz", "vz_est": "plant.vz",
                   "acc_z": "plant.az"}
"""The plant signal a recorded column measures or estimates, by the column's name ending."""


def _accuracy(results, name: str) -> float:
    """The RMS error of column ``name`` against the plant signal it measures or estimates
    (plant columns themselves and columns with no such truth: the RMS of the column)."""
    values = results[name]
    truth = next((results[t] for suffix, t in TRUTH_OF_SUFFIX.items()
                  if name.endswith(suffix) and t in results.columns and t != name), 0.0)
    return float(np.sqrt(np.mean((values - truth) ** 2)))


def _is_event_count(name: str) -> bool:
    """True for a column counting events (``n_rejected``, ``gps_rejected``...)."""
    signal = name.partition(".")[2]
    return signal.startswith("n_") or signal.endswith("_rejected")


ECOS_KNOWN_FAILURES = {
    "fault_demo_yang": (
        "YangFusionKF (fault_detection on) flies this loop's take-off at 9.96 m RMS height error "
        "under ECOS against 2.02 m in the Jacobi reference. Analysed (120 s, estimator "
        "diagnostics recorded): under both masters a sensor samples the plant a step of its "
        "own before its stamp (GNSS 0.1 s), and the take-off's +-10-16 m/s2 transients make "
        "the GPS vertical speed up to 1.6 m/s off against its sigma of 0.2 m/s: its gate rejects "
        "(74 samples in Jacobi, 268 in ECOS) and the samples that pass drive the accelerometer-"
        "bias state to -0.5..-1.0 m/s2 (truth +0.2). Under ECOS the aircraft touches the ground "
        "at 1.4 s (a speed jump no accelerometer sample sees), the bias stays wrong until 55 s "
        "and the height resets 8 times. Told the GNSS's delay (gps_delay 0.1 s, as "
        "jacobi_sensor_delays configures a Jacobi-type host) both engines fly the take-off "
        "without it: height 1.62 m under ECOS against 1.50 m "
        "(test_told_its_gnss_delay_yang_flies_the_take_off_in_ecos_as_in_the_reference), "
        "but the vertical speed still differs, 0.55 against 0.08 m/s RMS: under ECOS the "
        "loop's take-off overshoot still ends on the ground at 1.4 s (0.28 m above it at "
        "least under Jacobi), a speed jump the plant's az, the accelerometer's input, does "
        "not carry, and the GPS-speed gate rejects the GNSS until its reset"),
    "fault_flight_baro_step": (
        "the 40 s run's accuracy is its start: under the Jacobi reference AltitudeEKF (told the "
        "flight's flat terrain) starts on the 30 m GNSS at 0.2 s, one output row 25 m off "
        "(within its 15 m h_std) before the 5 mm laser pins it, 1.25 m of its 1.40 m RMS; "
        "under ECOS the held samples come due together and it starts on the laser: 0.64 m, "
        "2.2x more accurate than the reference. From 1 s on the two agree (0.61 m each), but "
        "YangFusionKF's take-off then differs (ECOS 1.76 m against 0.79 m: the take-off "
        "fragility analysed for fault_demo_yang; told the GNSS's 0.1 s delay, 1.86 m against "
        "1.56 m)"),
}
"""System -> why ECOS does not reach the reference's accuracy there (strict xfail: the test
fails as soon as the system passes)."""


@pytest.mark.parametrize("system", ENGINE_SYSTEMS)
def test_ecos_reproduces_the_jacobi_reference_bit_for_bit_or_with_the_same_accuracy(
        engine_runs, system, request):
    """ECOS agrees exactly except downstream of a slower-to-faster connection (none in a
    single-rate system), at multiples of each component's step. Downstream of one, an
    estimator sees samples stamped ahead of its clock: it holds them until due
    (estimators/base.py), so every engine fuses them at the same instant up to one step,
    and each of these columns has the same accuracy as in the reference: the RMS error of
    a height, speed or acceleration against the plant's own in that run, or the RMS of a
    diagnostic, within ENGINE_ACCURACY_RATIO either way. Event counters (``n_*``,
    ``*_rejected``) are no accuracy: which samples a gate rejects at take-off depends on the
    instant each is fused (XuSHAEKF re-acquires its laser once, 10 rejections, under the
    Jacobi reference's one-step-late samples and not under ECOS's); they must count up."""
    if system in ECOS_KNOWN_FAILURES:
        request.applymarker(pytest.mark.xfail(strict=True, reason=ECOS_KNOWN_FAILURES[system]))
    spec = build_system(system)
    ecos, reference = engine_runs(system, "ecos"), engine_runs(system, "altfusion-jacobi")
    divergent = ecos_divergent_components(spec)
    for name in reference.columns:
        component = spec.component(name.partition(".")[0])
        if component.name in divergent and _is_event_count(name):
            assert np.all(np.diff(ecos[name]) >= 0), name
            continue
        if component.name in divergent:
            ours, theirs = _accuracy(reference, name), _accuracy(ecos, name)
            assert theirs <= ENGINE_ACCURACY_RATIO * ours + 1e-9, (name, theirs, ours)
            assert ours <= ENGINE_ACCURACY_RATIO * theirs + 1e-9, (name, theirs, ours)
            continue
        every = round(component.step_size / (spec.output_interval or spec.base_step))
        _assert_identical(ecos, reference, [name], slice(0, None, max(every, 1)), "ecos")


def test_jacobi_sensor_delays_are_the_steps_of_the_sensors_the_samples_come_from(fmus):
    """Through the SensorFaults component to the sensor: YangFusionKF's and AltitudeEKF's
    GNSS delay the GnssReceiver's 0.1 s step, AltitudeEKF's baro delay the air data's 0.05 s;
    its range_delay, fed by a radio altimeter (0.2 s) and a laser (0.05 s), stays unset, and
    estimators without such parameters and a log replay's samples are left alone."""
    system = build_system("fault_flight_baro_step")
    configured = jacobi_sensor_delays(system, fmus)
    steps = {c.name: c.step_size for c in system.components}
    added = {f"{c.name}.{k}": v for c in configured.components for k, v in c.parameters.items()
             if k not in system.component(c.name).parameters}
    assert added == {"YangFusionKF.gps_delay": steps["gnss"],
                     "AltitudeEKF.gps_delay": steps["gnss"],
                     "AltitudeEKF.baro_delay": steps["air_data"]}
    assert steps["gnss"] == 0.1 and steps["air_data"] == 0.05
    replay = build_system("replay_auterion")
    assert jacobi_sensor_delays(replay, fmus) == replay


def test_told_its_gnss_delay_yang_flies_the_take_off_in_ecos_as_in_the_reference(
        fmus, engine_runs, tmp_path):
    """fault_demo_yang configured for a Jacobi-type host (``jacobi_sensor_delays``:
    YangFusionKF's gps_delay the GNSS's 0.1 s step): the height error under ECOS is within
    ENGINE_ACCURACY_RATIO of the Jacobi reference's, and each engine's is below its run
    without the delay (ECOS 1.62 m against 9.96 m, Jacobi 1.50 m against 2.02 m: the GPS
    vertical speed, one GNSS step older than its stamp at ±10-16 m/s², no longer drives the
    accelerometer-bias state wrong). Its vertical speed is in ECOS_KNOWN_FAILURES."""
    system = "fault_demo_yang"
    ssp = write_ssp(jacobi_sensor_delays(build_system(system), fmus), fmus,
                    tmp_path / f"{system}.ssp")
    stop = engine_run_seconds(system)
    ecos, jacobi = (run_in_subprocess(engine, ssp, stop) for engine in ("ecos",
                                                                        "altfusion-jacobi"))
    theirs, ours = _accuracy(ecos, "estimator.h_est"), _accuracy(jacobi, "estimator.h_est")
    assert theirs <= ENGINE_ACCURACY_RATIO * ours and ours <= ENGINE_ACCURACY_RATIO * theirs
    assert theirs < _accuracy(engine_runs(system, "ecos"), "estimator.h_est")
    assert ours < _accuracy(engine_runs(system, "altfusion-jacobi"), "estimator.h_est")


def _counters(system: str) -> list[str]:
    return [s for s in build_system(system).record if s.endswith(("_count", "_time"))]


@pytest.mark.parametrize("system", [s for s in ENGINE_SYSTEMS if _counters(s)])
def test_multi_rate_counters_come_out_exactly_as_in_our_runner(engine_runs, system):
    """Sample counts and time stamps depend on time only: libcosim running the exported OSP
    folder (each component at its own stepSize) gives exactly our ordered runner's."""
    _assert_identical(engine_runs(system, "libcosim-osp"), engine_runs(system, "altfusion"),
                      _counters(system), label="libcosim-osp")


def _loop_residual(system: SystemSpec, ordered) -> dict[str, float]:
    """Terms of the ordered/Jacobi difference of a loop closed on the true altitude."""
    controller = system.component("controller")
    params = controller.parameters
    kp, kd, ki = (params.get(k, d) for k, d in (("kp", 5.25), ("kd", 3.0), ("ki", 3.25)))
    # Peak altitude response of the closed loop (e''' + kd e'' + kp e' + ki e = 0 for the
    # error's integral) to a unit velocity kick: G (s).
    loop = control.ss([[0, 1, 0], [0, 0, 1], [-ki, -kp, -kd]], np.zeros((3, 1)),
                      [[0, 1, 0]], 0)
    times = np.linspace(0.0, 30.0, 30001)
    gain = float(np.abs(np.squeeze(control.initial_response(loop, times, [0, 0, 1]).outputs))
                 .max())
    dt = system.base_step
    profile = make_profile(params["profile"], params.get("profile_offset", 0.0),
                           params.get("profile_table", ""))
    grid = np.arange(round(ordered.time[-1] / dt) + 1) * dt
    reference = np.array([profile.reference(t) for t in grid])
    tracking = float(np.abs(ordered["plant.h"] - ordered["controller.h_ref"]).max())
    return {
        "vz": float(np.abs(reference[:, 1]).max()),
        "az": float(np.abs(reference[:, 2]).max()),
        "kick": gain * float(np.abs(np.diff(reference[:, 2])).max()) * dt,
        "tracking": tracking,
    }


@pytest.mark.parametrize("system", [s for s in ENGINE_SYSTEMS if s in JACOBI_LOOP_DELAY])
def test_ordered_and_jacobi_masters_differ_by_the_derived_loop_delay(engine_runs, system):
    """A Jacobi master hands the controller the altitude of the previous step: the loop gains
    a delay of L·dt (L = 1 base step for plant_yang2020), and its integral action makes the
    vehicle track the reference L·dt ahead. Writing Δh = h_J − h_O as
    [h_J(t) − h_ref(t+L·dt)] + [h_ref(t+L·dt) − h_ref(t)] − [h_O(t) − h_ref(t)]:

    * the middle term is at most max|vz_ref|·L·dt + ½·max|az_ref|·(L·dt)²
      (12 m/s · 0.01 s = 0.12 m for yang2020's profile; whang2008, base step 0.05 s:
      10 m/s · 0.05 s = 0.5 m, measured 0.503 m against a bound of 0.504 m);
    * the last is the ordered loop's own tracking error e_O (measured: ~1.2e-4 m);
    * the first is the Jacobi loop's tracking error: e_O again, plus the loop's response to
      its feedforward arriving L steps late: each step Δa of the reference acceleration
      kicks the velocity by Δa·L·dt, which the closed loop (poles −1, −1 ± 1.5j) turns into
      at most G·Δa·L·dt of altitude, G = 0.204 s (0.2 m/s² steps: 4.1e-4 m).

    The atmosphere samples the altitude of the previous step too, which cancels the lead:
    its altitude differs by at most 2·e_O + G·Δa·L·dt, times |dp/dh| = ρg ≤ 12.1 Pa/m."""
    spec, delay = build_system(system), JACOBI_LOOP_DELAY[system]
    ordered, jacobi = engine_runs(system, "altfusion"), engine_runs(system, "libcosim")
    terms = _loop_residual(spec, ordered)
    lag = delay * spec.base_step
    residual = 2 * terms["tracking"] + terms["kick"] * delay
    h_bound = terms["vz"] * lag + 0.5 * terms["az"] * lag**2 + residual
    h_diff = np.abs(jacobi["plant.h"] - ordered["plant.h"]).max()
    assert h_diff <= h_bound
    assert h_diff >= terms["vz"] * lag - residual, "the one-step lead must be there"
    if "atmosphere.p_static" not in ordered.columns:
        return  # whang2008 records no pressure; its air data is checked at the base step below
    density = ordered["atmosphere.p_static"] / (R_AIR * ordered["atmosphere.T_air"])
    p_bound = (density * G0).max() * residual
    assert np.abs(jacobi["atmosphere.p_static"] - ordered["atmosphere.p_static"]).max() \
        <= p_bound


# Sensor and estimator outputs of the ordered and the Jacobi master, recorded at the base step
# (the engine runs record every 0.1 s or 0.2 s; our Jacobi master equals libcosim and ECOS bit
# for bit, tested above). Each sensor component is stepped at its sample period T: ordered, it
# samples its input at the end of its step; Jacobi, the value latched at the step's start, T
# earlier. Sample instants, counts and every random draw are the same in both runs.

BASE_STEP_RECORD = {
    "whang2008": ("atmosphere.p_static", "atmosphere.T_air", "air_data.baro_count"),
    "yang2020": ("atmosphere.p_static", "controller.vz_ref", "controller.az_ref",
                 "gnss.gps_count", "radar.radar_count", "radar.radar_valid",
                 "accelerometer.acc_count", "air_data.baro_count"),
}
EPS = np.finfo(float).eps


@pytest.fixture(scope="module")
def base_step_runs(fmus):
    """Our ordered and Jacobi runs of a system's first ENGINE_RUN_SECONDS, every base step."""
    cache: dict[str, dict[str, object]] = {}

    def get(system: str):
        if system not in cache:
            spec = build_system(system)
            spec = replace(spec, output_interval=spec.base_step,
                           record=tuple(dict.fromkeys(spec.record + BASE_STEP_RECORD[system])))
            stop = min(spec.stop_time, ENGINE_RUN_SECONDS)
            cache[system] = {master: simulate(spec, fmus, stop_time=stop, master=master)
                             for master in MASTERS}
        return cache[system]
    return get


def _sensor_error_difference(runs, output: str, truth: str, every: int) -> float:
    """max |e_J − e_O| of a sensor's error relative to the truth it sampled, over its samples
    (every ``every`` base steps): the ordered sensor samples the truth of the same row, the
    Jacobi one that of ``every`` rows earlier. Also checks that the alignment matters: against
    the same row, the Jacobi error differs by more than 1e-9."""
    ordered, jacobi = runs["ordered"], runs["jacobi"]
    rows = np.arange(every, len(ordered.time), every)
    e_ordered = ordered[output][rows] - ordered[truth][rows]
    e_jacobi = jacobi[output][rows] - jacobi[truth][rows - every]
    misaligned = jacobi[output][rows] - jacobi[truth][rows]
    assert np.abs(misaligned - e_ordered).max() > 1e-9, output
    return float(np.abs(e_jacobi - e_ordered).max())


def _additive_tolerance(runs, output: str, truth: str, roundings: int) -> float:
    """Float rounding of y = truth + error (zero terms such as a bias of 0.0 add exactly):
    each of the ``roundings`` operations of magnitude ≤ M errs by ≤ ½ ulp(M), in each run,
    and the test's own subtraction once more: |e_J − e_O| ≤ (roundings + 1)·ulp(M)."""
    magnitude = max(np.abs(runs[m][c]).max() for m in MASTERS for c in (output, truth))
    return (roundings + 1) * float(np.spacing(magnitude))


def _baro_tolerance(air_data: AirDataParams, baro_h_max: float) -> float:
    """|e_J − e_O| of baro_h − h_cal(p_static sampled) = noise + rounding + quantization.

    * baro_h = h_cal(Q(p_cal(h_cal(p) + n))): with no drift, bias or wind (asserted by the
      callers) the sample is h_cal(p) + n exactly up to rounding and quantization;
    * quantization: |Q(p') − p'| ≤ res/2, i.e. res/2·|dh/dp| of height, |dh/dp| = R·T/(g·p)
      of the calibration atmosphere, largest at the highest reading: both runs, res·|dh/dp|;
    * round trip h → p_cal → h_cal: about 18 roundings reach p_cal's pressure relatively
      (the power's base errs by ~3ε, amplified by its exponent g/(|Γ|R) = 5.26), i.e.
      18ε·R·T0/g of height; h_cal's power term errs by ~3ε absolutely, times T0/|Γ|; adding
      the noise and the test's subtraction: 2 ulp(h); all twice (two runs)."""
    p = air_data
    pressure = pressure_at(baro_h_max, p.P0, p.T0, p.lapse_rate, p.H0)
    temperature = p.T0 + p.lapse_rate * (baro_h_max - p.H0)
    quantization = p.pressure_resolution * R_AIR * temperature / (G0 * pressure)
    round_trip = (18 * R_AIR * p.T0 / G0 + 3 * p.T0 / abs(p.lapse_rate)) * EPS \
        + 2 * float(np.spacing(baro_h_max))
    return quantization + 2 * round_trip


def _calibrated_height(air_data: AirDataParams, pressure: np.ndarray) -> np.ndarray:
    p = air_data
    return np.array([height_from_pressure(x, p.P0, p.T0, p.lapse_rate, p.H0) for x in pressure])


def _air_data(spec: SystemSpec) -> AirDataParams:
    params = AirDataParams(**spec.component("air_data").parameters)
    assert (params.drift_rate, params.drift_variance_rate, params.pressure_bias) == (0, 0, 0)
    return params


def _baro_error_difference(runs, air_data: AirDataParams, every: int) -> float:
    """As _sensor_error_difference for baro_h against h_cal of the pressure it sampled."""
    ordered, jacobi = runs["ordered"], runs["jacobi"]
    rows = np.arange(every, len(ordered.time), every)
    e_ordered = ordered["air_data.baro_h"][rows] \
        - _calibrated_height(air_data, ordered["atmosphere.p_static"][rows])
    e_jacobi = jacobi["air_data.baro_h"][rows] \
        - _calibrated_height(air_data, jacobi["atmosphere.p_static"][rows - every])
    return float(np.abs(e_jacobi - e_ordered).max())


def _reference(spec: SystemSpec, time: np.ndarray) -> np.ndarray:
    params = spec.component("controller").parameters
    profile = make_profile(params["profile"], params.get("profile_offset", 0.0),
                           params.get("profile_table", ""))
    return np.array([profile.reference(t) for t in time])


def _steady_climb(reference: np.ndarray, history: int) -> np.ndarray:
    """Rows whose reference acceleration was 0 over the last ``history`` base steps."""
    still = (reference[:, 2] == 0.0).astype(int)
    window = np.convolve(still, np.ones(history + 1, dtype=int))[:len(still)]
    return window == history + 1


def test_whang2008_jacobi_sensors_keep_their_errors_and_the_estimator_lags(base_step_runs):
    """whang2008 (loop on the truth, L = 1; the altitude lead is checked above), sensors:

    * every random draw is the same: the weather (lapse rate redrawn every 10 s at the same
      ticks) is identical, and each sensor's error relative to the input it sampled (Jacobi:
      one sensor step earlier, T_B = 0.2 s for the air data, T_G = 1 s for the GPS) agrees to
      float rounding: gps_h − h and baro_T − T_air (additive, one rounding: 2 ulps),
      baro_h − h_cal(p_static) (through pressure: the round-trip rounding of _baro_tolerance;
      no quantization in whang2008).

    Estimator: the Jacobi estimator fuses at t + T_B the samples the ordered one fuses at t, so
    compare δx(t) = x_J(t + T_B) − x_O(t). Those samples carry the same errors; their truths
    are older: the air data's by T_B (sampled at t − T_B of the altitude of t − T_B − dt, the
    loop's lead dt making up for the dt), the GPS's by T_G − dt. In the steady climb (vz_ref =
    10 m/s, no reference acceleration over the last T_G + T_B) the baro truth is vz·T_B lower,
    the GPS truth vz·(T_G − dt) lower. The GA filter estimates the bias b from z = h^B − h^GPS
    with a weight w in [0, 1] and compensates h^c = (h^B − b)/(1 + a); the alpha-beta filter
    passes a constant offset of h^c unchanged. So, averaged over the window,

        δh_comp, δh_est ∈ [−vz·(T_G − dt), −vz·T_B],   δb ∈ [0, vz·(T_G − dt − T_B)]

    widened by m = max|a|·vz·T_G (the scale factor's share of the offsets; the ordered run's
    estimate, 0.014) + 2·tracking + kick (the lead's residual, see _loop_residual). Measured
    means: δh_est −9.47 m, δh_comp −9.47 m, δb 7.35 m (w ≈ 0.98: Q_b is large) against
    [−9.65, −1.85] and [−0.15, 7.65]. Pointwise the filter is not bounded by this: the one air-data
    sample after each lapse-rate change sees the old weather in the Jacobi run (up to ~3 K and
    ~5 m at 1 km), and the slow scale factor keeps that (|δa| up to 0.005: δh up to 11 m)."""
    system = "whang2008"
    spec, runs = build_system(system), base_step_runs(system)
    ordered, jacobi = runs["ordered"], runs["jacobi"]
    dt = spec.base_step
    t_b, t_g = (round(spec.component(n).step_size / dt) for n in ("air_data", "gnss"))
    assert np.array_equal(jacobi["atmosphere.lapse_rate_actual"],
                          ordered["atmosphere.lapse_rate_actual"])
    for counter in ("gnss.gps_count", "air_data.baro_count"):
        assert np.array_equal(jacobi[counter], ordered[counter]), counter
    for output, truth, every in (("gnss.gps_h", "plant.h", t_g),
                                 ("air_data.baro_T", "atmosphere.T_air", t_b)):
        difference = _sensor_error_difference(runs, output, truth, every)
        assert difference <= _additive_tolerance(runs, output, truth, 1), (output, difference)
    air_data = _air_data(spec)
    assert air_data.pressure_resolution == 0 and air_data.temperature_resolution == 0
    baro_bound = _baro_tolerance(air_data, np.abs(ordered["air_data.baro_h"]).max())
    assert _baro_error_difference(runs, air_data, t_b) <= baro_bound

    reference = _reference(spec, ordered.time)
    steady = _steady_climb(reference, t_g + t_b)[:-t_b]
    vz = reference[:-t_b, 1][steady]
    assert np.ptp(vz) == 0 and steady.sum() > 1000
    vz = float(vz[0])
    terms = _loop_residual(spec, ordered)
    margin = (np.abs(ordered["estimator.scale_factor"]).max() * vz * t_g * dt
              + 2 * terms["tracking"] + terms["kick"])
    lags = {"baro": vz * t_b * dt, "gps": vz * (t_g - 1) * dt}

    def shifted_mean(name: str) -> float:
        return float((jacobi[name][t_b:] - ordered[name][:-t_b])[steady].mean())

    for name in ("estimator.h_comp", "estimator.h_est"):
        assert -lags["gps"] - margin <= shifted_mean(name) <= -lags["baro"] + margin, name
    assert -margin <= shifted_mean("estimator.bias") <= lags["gps"] - lags["baro"] + margin


def test_yang2020_jacobi_sensors_keep_their_errors_and_the_loop_leads(base_step_runs):
    """yang2020 flies on YangFusionKF's estimate: under Jacobi every connection of the loop
    plant -> sensor -> estimator -> controller adds a latch, and a sensor stepped at T samples
    the plant T earlier (GNSS 0.1 s, radio altimeter 0.2 s). Extra delay of each path, in base
    steps (sensor step + estimator + controller): accelerometer 1+1+1 = 3, barometer 4 (the
    atmosphere too), GNSS 10+1+1 = 12, radio altimeter 20+1+1 = 22.

    (a) Sensors: same draws, same sample instants (counts equal), and each error relative to
    the truth it sampled agrees to float rounding: gps_h − h, gps_vz − vz, radar_h − h (one
    rounding: 2 ulps), acc_z − az (az + g, + noise, − g: 3 ulps of g + max|az|, 26.7 m/s² in
    the start-up transient); the barometer through pressure to its 1.2 Pa quantization:
    res·R·T/(g·p) at the highest reading (0.11 m; measured 0.109, the two runs' quantization
    errors are independent and uniform over 12000 samples) plus the round trip.

    (b) Altitude, in the steady climb (vz_ref = 12 m/s, no reference acceleration over the last
    L_max = 22 steps; before it the estimator's start-up, a 30 m first estimate, dominates).
    The controller makes its feedback track the reference, so the truth leads the reference
    by what the estimate lags the truth: a linear unbiased filter fed truths delayed by the
    paths' delays lags by a weighted mean of them, so Δh = h_J − h_O ≈ vz·L·dt with L in
    [3, 22] steps. Residuals, measured on the ordered run: the Jacobi loop flies on the same
    noise up to L_max steps later, r = max|ε_O(t) − ε_O(t − L_max·dt)| of its estimate error
    ε_O = h_est − h (0.15 m); each loop's tracking of its feedback, 2·max|h_est − h_ref| (0.18 m
    each); the reference's acceleration step kick G·Δa·L_max·dt (9e-3 m). Pointwise
    |Δh| ≤ vz·L_max·dt + residual (2.64 + 0.52 m; measured ≤ 2.24 m). Averaged over the window
    the noise terms cancel but for the telescoped ends of r (2·L_max/N·max|ε_O|) and the mean
    tracking errors (2·|mean(h_est − h_ref)|), so mean Δh ∈ [vz·3·dt, vz·22·dt] = [0.36,
    2.64] m widened by these: the lead is there (measured mean 2.10 m, ≈ 17.5
    steps: the estimate leans on the GNSS and the radio altimeter)."""
    system = "yang2020"
    spec, runs = build_system(system), base_step_runs(system)
    ordered, jacobi = runs["ordered"], runs["jacobi"]
    dt = spec.base_step
    steps = {name: round(spec.component(name).step_size / dt)
             for name in ("gnss", "radar", "accelerometer", "air_data")}
    for counter in ("gnss.gps_count", "radar.radar_count", "radar.radar_valid",
                    "accelerometer.acc_count", "air_data.baro_count"):
        assert np.array_equal(jacobi[counter], ordered[counter]), counter
    for output, truth, sensor, roundings in (
            ("gnss.gps_h", "plant.h", "gnss", 1), ("gnss.gps_vz", "plant.vz", "gnss", 1),
            ("radar.radar_h", "plant.h", "radar", 1),
            ("accelerometer.acc_z", "plant.az", "accelerometer", 2)):
        difference = _sensor_error_difference(runs, output, truth, steps[sensor])
        tolerance = _additive_tolerance(runs, output, truth, roundings)
        if sensor == "accelerometer":  # the magnitude of its sums is g + |az|
            magnitude = G0 + max(np.abs(runs[m]["plant.az"]).max() for m in MASTERS)
            tolerance = 3 * float(np.spacing(magnitude))
        assert difference <= tolerance, (output, difference, tolerance)
    air_data = _air_data(spec)
    baro_bound = _baro_tolerance(air_data, np.abs(ordered["air_data.baro_h"]).max())
    baro_difference = _baro_error_difference(runs, air_data, steps["air_data"])
    assert baro_difference <= baro_bound
    assert baro_difference > baro_bound / 2, "the quantization difference must be there"

    shortest = steps["accelerometer"] + 2
    longest = steps["radar"] + 2
    reference = _reference(spec, ordered.time)
    steady = _steady_climb(reference, longest)
    steady[:longest] = False
    vz = reference[steady, 1]
    assert np.ptp(vz) == 0 and steady.sum() > 1000
    vz = float(vz[0])
    error = ordered["estimator.h_est"] - ordered["plant.h"]
    tracking = ordered["estimator.h_est"] - ordered["controller.h_ref"]
    drift = np.abs(error[longest:] - error[:-longest])[steady[longest:]].max()
    kick = _loop_residual(spec, ordered)["kick"] / dt * longest * dt
    residual = drift + 2 * np.abs(tracking[steady]).max() + kick
    h_diff = (jacobi["plant.h"] - ordered["plant.h"])[steady]
    assert np.abs(h_diff).max() <= vz * longest * dt + residual
    mean_residual = (2 * longest / steady.sum() * np.abs(error[steady]).max()
                     + 2 * abs(tracking[steady].mean()) + kick)
    assert vz * shortest * dt - mean_residual <= h_diff.mean() \
        <= vz * longest * dt + mean_residual


# ------------------------------------------------------------------------------ multi-rate


@pytest.fixture(scope="module")
def sample_hold_fmu(tmp_path_factory, fmus):
    """The test-fixture sensor FMU (fixtures/sample_hold_slave.py), built from this core."""
    folder = tmp_path_factory.mktemp("fixture_fmus")
    script = ROOT / "system_tests" / "fixtures" / "sample_hold_slave.py"
    return Path(builder.build_fmu(script, folder))


def multi_rate_system() -> SystemSpec:
    """The plant loop at 0.01 s, a 5 Hz baro and a 1 Hz GPS (sample-and-hold sensors stepped
    at their sample period) and the BaselineKF at 0.2 s fusing them by their counts."""
    return SystemSpec(
        name="multi_rate", description="plant at 0.01 s, sensors at 0.2 s and 1 s, KF at 0.2 s",
        components=(*plant_components("yang2020"),
                    ComponentSpec("baro", "SampleHold", 0.2, {"sample_period": 0.2}),
                    ComponentSpec("gps", "SampleHold", 1.0, {"sample_period": 1.0}),
                    ComponentSpec("kf", "BaselineKF", 0.2, {"R_gps": 25.0})),
        connections=(*plant_connections(),
                     Connection("plant.h", "baro.u"), Connection("plant.h", "gps.u"),
                     Connection("baro.y", "kf.baro_h"), Connection("baro.y_count", "kf.baro_count"),
                     Connection("gps.y", "kf.gps_h"), Connection("gps.y_count", "kf.gps_count")),
        stop_time=60.0, output_interval=0.2,
        record=("plant.h", "controller.h_ref", "baro.y", "baro.y_count", "baro.y_time", "gps.y",
                "gps.y_count", "gps.y_time", "kf.h_est", "kf.h_std"),
    )


@pytest.fixture(scope="module")
def multi_rate(tmp_path_factory, fmus, sample_hold_fmu):
    folder = tmp_path_factory.mktemp("multi_rate")
    system = multi_rate_system()
    paths = {**fmus, "SampleHold": sample_hold_fmu}
    ssp = write_ssp(system, paths, folder / "multi_rate.ssp")
    assert ssp_problems(ssp) == []
    write_osp(system, paths, folder / "osp")
    runs = {"ordered": simulate(system, paths), "jacobi": simulate(system, paths, master="jacobi")}
    for engine in ("libcosim-osp", "libcosim", "ecos"):
        runs[engine] = run_in_subprocess(engine, ssp, osp=folder / "osp")
    return system, runs


def test_libcosim_runs_the_osp_export_with_each_sensor_at_its_own_rate(multi_rate):
    """The sensors refuse any doStep other than their own step (0.2 s, 1 s), so a complete run
    shows the rates were honoured; counters and time stamps equal our runner's exactly (they
    depend on time only), and every signal equals the Jacobi reference bit for bit."""
    _, runs = multi_rate
    osp, ordered = runs["libcosim-osp"], runs["ordered"]
    for counter in ("baro.y_count", "baro.y_time", "gps.y_count", "gps.y_time"):
        _assert_identical(osp, ordered, [counter], label="libcosim-osp")
    assert osp["baro.y_count"][-1] == 60.0 / 0.2 + 1 and osp["gps.y_count"][-1] == 60 + 1
    _assert_identical(osp, runs["jacobi"], label="libcosim-osp")
    _assert_identical(runs["libcosim"], runs["jacobi"], label="libcosim")


def test_a_jacobi_sensor_samples_the_plant_one_sensor_step_late(multi_rate):
    """A sensor stepping over (t - T, t] latches its input at t - T: in a Jacobi master it
    samples the altitude of its previous step, T = 0.2 s for the baro, less the loop's
    one-base-step lead. So |y_J − y_O| ≤ max|vz|·(T − dt) + 2 mm (the loop residual of the
    closed-loop test, 6.5e-4 m, rounded up), while the counters agree exactly."""
    system, runs = multi_rate
    ordered, jacobi = runs["ordered"], runs["jacobi"]
    vz_max = 0.2 * 60.0  # yang2020's profile accelerates at 0.2 m/s² for the first 60 s
    for sensor, period in (("baro", 0.2), ("gps", 1.0)):
        diff = np.abs(jacobi[f"{sensor}.y"] - ordered[f"{sensor}.y"]).max()
        assert diff <= vz_max * (period - system.base_step) + 2e-3, sensor
        assert np.array_equal(jacobi[f"{sensor}.y_count"], ordered[f"{sensor}.y_count"])


def test_ecos_honours_the_step_sizes_but_feeds_faster_consumers_early(multi_rate):
    """ECOS steps each component at its own rate (the run completes) and agrees bit for bit
    with the Jacobi reference for the plant loop and the sensors at multiples of their steps.
    It shows a slow component's output as soon as the component has stepped: at t = 0.2 s the
    1 s GPS already reports its sample of t = 1 s (count 2), where libcosim and we still hold
    the t = 0 sample; so the 0.2 s filter fed by the GPS differs."""
    system, runs = multi_rate
    ecos, jacobi = runs["ecos"], runs["jacobi"]
    assert ecos_divergent_components(system) == {"kf"}
    _assert_identical(ecos, jacobi, ["plant.h", "baro.y", "baro.y_count"], label="ecos")
    _assert_identical(ecos, jacobi, ["gps.y", "gps.y_count", "gps.y_time"], slice(0, None, 5),
                      "ecos")
    row = 1  # t = 0.2 s
    assert (ecos["gps.y_count"][row], jacobi["gps.y_count"][row]) == (2.0, 1.0)
    assert not np.array_equal(ecos["kf.h_est"], jacobi["kf.h_est"])


# ------------------------------------------------------------------------------ container


@pytest.mark.parametrize("system", SINGLE_RATE_SYSTEMS)
def test_the_whole_system_as_one_container_fmu_matches_the_multi_fmu_run(fmus, tmp_path,
                                                                         system):
    """The container steps its members in our upstream-first order (sequential mode), so
    fmpy's simulate_fmu on it reproduces our ordered run bit for bit from the first step on.
    At t = 0 the toolbox initializes a member fed through a loop (the plant's thrust) without
    the value the loop gives it ("Loop of links ... initialized without the values its inputs
    get from the loop"): the plant's initial acceleration reads 0 (thrust 0, resting on the
    ground) where ours reads the commanded 0.2 m/s²; nothing else differs."""
    spec = replace(build_system(system), stop_time=engine_run_seconds(system))
    container = build_container(spec, [c.name for c in spec.components], fmus,
                                tmp_path / "Whole.fmu")
    assert fmu_problems(container.path) == []
    packed = simulate_in_subprocess(container, spec.stop_time)
    ours = simulate(replace(spec, output_interval=container.step_size), fmus)
    _assert_identical(packed, ours, list(container.outputs), slice(1, None), "container")
    rank = {name: i for i, name in enumerate(container.members)}
    loop_fed = {c.end.partition(".")[0] for c in spec.connections
                if rank[c.start.partition(".")[0]] > rank[c.end.partition(".")[0]]}
    at_start = [n for n in container.outputs if packed[n][0] != ours[n][0]]
    assert {n.partition(".")[0] for n in at_start} <= loop_fed, at_start
    if system == "plant_yang2020":
        assert at_start == ["plant.az"]


@pytest.mark.parametrize(("system", "members"),
                         [(s, m) for s, subs in CONTAINER_SUBSYSTEMS.items() for m in subs])
def test_a_subsystem_container_driven_by_the_rest_of_the_system_matches(fmus, tmp_path,
                                                                        system, members):
    """The container's inputs replay the multi-FMU run's signals, one row early for inputs our
    runner reads at the end of the step (fmpy applies inputs before each doStep); its
    outputs then equal the multi-FMU run bit for bit from the first step on. fmpy also
    applies that first row during initialization, so at t = 0 the outputs of members fed
    through a feedthrough input (the controller's thrust, the atmosphere's pressure and
    temperature) see the altitude of t = 0.01 s."""
    spec = build_system(system)
    container = build_container(spec, list(members), fmus, tmp_path / "Subsystem.fmu")
    ours = simulate(replace(spec, output_interval=container.step_size,
                            record=tuple({*container.inputs.values(), *container.outputs})),
                    fmus)
    packed = simulate_in_subprocess(container, spec.stop_time,
                                    input_table(container, ours, spec.stop_time))
    _assert_identical(packed, ours, list(container.outputs), slice(1, None), "container")
    fed = {i.partition(".")[0] for i in container.feedthrough_inputs}
    at_start = {n for n in container.outputs if packed[n][0] != ours[n][0]}
    assert at_start <= {n for n in container.outputs if n.partition(".")[0] in fed}, at_start


# ------------------------------------------------------------------------------ non-Python host


def test_ecos_command_line_host_runs_every_fmu_in_a_proxy_process(ssp_files, engine_runs):
    """``ecos simulate`` (C++, no Python inside) with each FMU in its own ``proxyfmu`` process,
    libpython preloaded: it agrees with ECOS in process to the 6 decimals of its CSV
    (|Δ| ≤ 0.5e-6 + one float spacing at 1e5 Pa)."""
    system = "plant_yang2020"
    proxy = run_in_subprocess("ecos-proxy", ssp_files[system], stop_time=60.0)
    in_process = engine_runs(system, "ecos")
    rows = len(proxy.time)
    assert rows == 601 and np.array_equal(proxy.time, in_process.time[:rows])
    for name in in_process.columns:
        assert np.abs(proxy[name] - in_process[name][:rows]).max() <= 0.5e-6 + 2e-11, name


def test_the_command_line_host_records_the_last_row_and_leaves_nothing_in_tmp(tmp_path):
    """``ecos simulate`` adds its steps up in floats: asked to stop at 1 s, yang2020 (steps of
    0.01, 0.1 and 0.2 s) stopped a step short and the run failed ("10 rows, expected 11").
    And ECOS unpacks the archive and each proxyfmu its FMU and socket in the temporary
    folder, and leaves them: a run leaves nothing in its TMPDIR."""
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    csv = tmp_path / "proxy.csv"
    done = subprocess.run([sys.executable, "-m", "altfusion.interop", "run", "--engine",
                           "ecos-proxy", "--stop", "1", "--csv", str(csv),
                           str(MODELS / "yang2020.ssp")],
                          capture_output=True, text=True, timeout=300, cwd=ROOT,
                          env={**os.environ, "TMPDIR": str(scratch)})
    assert done.returncode == 0, done.stderr[-2000:]
    assert np.array_equal(Results.from_csv(csv).time, np.arange(11) / 10)   # tick n: n/10
    assert list(scratch.iterdir()) == []


def test_without_preloaded_libpython_the_proxy_cannot_load_the_fmus(ssp_files, tmp_path):
    """The documented requirement is real: pythonfmu's library takes Python from its host."""
    from altfusion.interop.proxy import ecos_binaries, proxy_ssp

    proxied = proxy_ssp(ssp_files["plant_yang2020"], tmp_path / "proxied.ssp")
    env = {k: v for k, v in os.environ.items() if k != "LD_PRELOAD"}
    env["LD_LIBRARY_PATH"] = python_environment()["LD_LIBRARY_PATH"]   # libtbb, not libpython
    completed = subprocess.run(
        [str(ecos_binaries() / "ecos"), "simulate", "--path", str(proxied), "--stepSize", "0.01",
         "--stopTime", "0.1", "--noCsv"], cwd=tmp_path, env=env, capture_output=True, text=True,
        timeout=120)
    assert completed.returncode != 0
    assert "Unable to bind" in completed.stdout + completed.stderr
    assert python_environment()["LD_PRELOAD"].endswith(".so.1.0")


def test_a_failing_engine_run_is_a_clear_error(tmp_path):
    with pytest.raises(EngineError, match="libcosim run of .* failed"):
        run_in_subprocess("libcosim", tmp_path / "missing.ssp")


@pytest.mark.parametrize(("engine", "message"), [
    ("libcosim", r"'plant'.*'mass' = -1\.0: must be > 0"),
    ("ecos", r"'plant'.*'mass' = -1\.0: must be > 0"),
])
def test_a_bad_parameter_fails_the_engine_run_naming_it(fmus, tmp_path, engine, message):
    """libcosim aborts the process on the fmi2Error of fmi2ExitInitializationMode (the native
    shim returns the error the FMU logs) and ECOS 0.7.2 ignores a failing doStep, so the
    adapters check the parameters on the core objects first."""
    system = build_system("plant_yang2020").with_parameters({"plant.mass": -1.0})
    ssp = write_ssp(system, fmus, tmp_path / "bad.ssp")
    with pytest.raises(EngineError, match=message):
        run_in_subprocess(engine, ssp, stop_time=1.0)


KEPT_SLAVES = """
import atexit, gc, sys
from pathlib import Path
from altfusion.cosim.instances import release_mapped_pythonfmu_state
from altfusion.interop.__main__ import run_engine

atexit.register(release_mapped_pythonfmu_state)
for _ in range(3):
    run_engine(sys.argv[1], Path(sys.argv[2]), 1.0)
    gc.collect()
    print("slaves", sum(1 for o in gc.get_objects()
                        if any(c.__name__ == "CoreSlave" for c in type(o).__mro__)), flush=True)
"""
"""Three runs of an engine in one process, each followed by the number of our FMUs' slave
objects still alive."""


@pytest.mark.parametrize("engine", ["libcosim", "ecos"])
def test_an_engine_run_frees_every_slave_object_it_made(ssp_files, engine):
    """The pythonfmu state of the FMU libraries is released after the engine's execution
    has freed its instances: released before, pythonfmu 0.7.0's fmi2FreeInstance kept every
    slave object (8 per run of yang2020, ~3 MiB with their cores), so that a campaign of
    runs in one process grew without bound."""
    completed = subprocess.run([sys.executable, "-c", KEPT_SLAVES, engine,
                                str(ssp_files["yang2020"])], capture_output=True, text=True,
                               timeout=600, cwd=ROOT)
    assert completed.returncode == 0, completed.stderr[-2000:]
    counts = [line.split()[1] for line in completed.stdout.splitlines()
              if line.startswith("slaves ")]          # libcosim logs on stdout too
    assert counts == ["0", "0", "0"]
