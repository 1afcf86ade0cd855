"""Build every FMU in fmu_src/ into models/<Name>.fmu and every catalog system into
models/<name>.ssp and models/<name>/OspSystemStructure.xml (libcosim's format, with copies of
its FMUs); validate them; regenerate the generated documentation.

    python build_fmu.py            build what is missing or older than its sources
    python build_fmu.py --force    rebuild everything
    python build_fmu.py --check    exit 1 if a built FMU is missing or older than its sources
    python build_fmu.py --plots    also rerun the FMU pages' reference plots (docs/fmus/*.png)
                                   and the replay of docs/replay.md (its plot and table)

Every FMU bundles a private copy of the ``altfusion`` modules its slave script needs, under a
name of its own (``altfusion.fmi.bundle``: PythonFMU issue #228), and its linux64 binary is
our native shim in front of pythonfmu's library (``altfusion.fmi.shim``, compiled with the
system C compiler ``cc``: the build fails with that reason without one). Each FMU is validated
with fmpy's validator and each SSP against the SSP 1.0 schema; any problem fails the build.
"""

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
FMU_SRC = HERE / "fmu_src"
MODELS = HERE / "models"
CORE = HERE / "altfusion"
DOCS = HERE / "docs"
FMU_TEXTS = FMU_SRC / "docs"
STAGE = HERE / "build" / "fmu_stage"
"""The private core copy and the slave scripts renamed to import it, as bundled."""
SHIM_BUILD = HERE / "build" / "shim"
"""The compiled native shim (``altfusion.fmi.shim``)."""


def slave_scripts() -> list[Path]:
    return sorted(FMU_SRC.glob("*_slave.py"))


def model_class(script: Path) -> type:
    """The slave class defined in the script."""
    from pythonfmu.builder import get_model_class

    if str(script.parent) not in sys.path:
        sys.path.insert(0, str(script.parent))
    return get_model_class(script)


def model_name(script: Path) -> str:
    """The FMU's model name: the slave class defined in the script."""
    return model_class(script).__name__


def bundled_files(script: Path) -> list[Path]:
    """Files or folders (the slave's ``bundled_files``, relative to the repository) that the
    FMU carries in its resources folder, e.g. the flight logs of LogReplay."""
    return [HERE / name for name in getattr(model_class(script), "bundled_files", ())]


def sources_mtime(script: Path) -> float:
    core = [p for p in CORE.rglob("*.py") if "__pycache__" not in p.parts]
    bundled = [f for p in bundled_files(script) for f in ([p] if p.is_file() else p.rglob("*"))]
    from altfusion.fmi.shim import SOURCE as SHIM_SOURCE

    inputs = [script, Path(__file__), SHIM_SOURCE, *core, *bundled]
    return max(p.stat().st_mtime for p in inputs)


def stale(script: Path, fmu: Path) -> bool:
    return not fmu.exists() or fmu.stat().st_mtime < sources_mtime(script)


def stage_core() -> Path:
    """The private copy of the core every FMU bundles (``altfusion.fmi.bundle``), its hot
    modules compiled (``altfusion.compile_core``)."""
    from altfusion.compile_core import compile_core
    from altfusion.fmi.bundle import stage_core as stage
    from altfusion.version import CORE_VERSION

    core = stage(CORE, slave_scripts(), CORE_VERSION, STAGE)
    compile_core(core)
    return core


def build_fmu(script: Path, dest: Path = MODELS, core: Path | None = None,
              shim: Path | None = None) -> Path:
    """Build the FMU of ``script`` carrying the private ``core`` copy (default: staged now by
    :func:`stage_core`), its linux64 binary the native ``shim`` (default: compiled now)."""
    from pythonfmu.builder import FmuBuilder

    from altfusion.fmi.bundle import stage_script
    from altfusion.fmi.shim import compile_shim, install_shim

    core = core or stage_core()
    shim = shim or compile_shim(SHIM_BUILD)
    staged = stage_script(script, core, STAGE)
    if str(STAGE) not in sys.path:
        sys.path.insert(0, str(STAGE))
    fmu = Path(FmuBuilder.build_FMU(
        staged, dest=dest, project_files=[core, *bundled_files(script)],
        canGetAndSetFMUstate=True, canSerializeFMUstate=True,
        canHandleVariableCommunicationStepSize=True,
    ))
    install_shim(fmu, shim)
    return fmu


def validate_fmu(fmu: Path) -> list[str]:
    from fmpy.validation import validate_fmu as fmpy_validate

    return fmpy_validate(str(fmu))


def build_systems(fmu_paths: dict[str, Path]) -> list[Path]:
    from fmpy.ssp.ssd import read_ssd

    from altfusion.cosim.ssp import write_ssp
    from altfusion.interop.osp import write_osp
    from altfusion.systems import SYSTEMS

    written = []
    for name, make in SYSTEMS.items():
        system = make()
        path = write_ssp(system, fmu_paths, MODELS / f"{name}.ssp")
        read_ssd(str(path), validate=True)
        written += [path, write_osp(system, fmu_paths, MODELS / name)]
    return written


def write_if_changed(path: Path, text: str) -> None:
    if not path.exists() or path.read_text() != text:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
        print(f"wrote {path.relative_to(HERE)}")


def replay_docs(log: Path, fmu_paths: dict[str, Path], png: Path, page: Path) -> None:
    """Replay ``log`` with every catalog estimator as ``altfusion replay`` does, copy its
    plot to ``png`` and its summary table into ``page`` between the markers
    ``altfusion.docs.REPLAY_SUMMARY`` (here, since the docs generator sits beside replay/ in
    the layers and may not import it)."""
    import shutil
    import tempfile

    from altfusion.atomic import write_text
    from altfusion.docs import REPLAY_SUMMARY, replace_generated
    from altfusion.estimators.registry import ESTIMATOR_CLASSES
    from altfusion.replay.run import plan_replay, run_replay

    with tempfile.TemporaryDirectory(prefix="altfusion_replay_docs_") as folder:
        replay = run_replay(plan_replay(log, list(ESTIMATOR_CLASSES), fmu_paths), fmu_paths,
                            Path(folder))
        plot = next(f for f in replay.files if f.suffix == ".png")
        table = next(f for f in replay.files if f.name.endswith("_summary.md")).read_text()
        shutil.copyfile(plot, png)
    write_text(page, replace_generated(page.read_text(), REPLAY_SUMMARY, table))


def build_docs(fmu_paths: dict[str, Path], plots: bool = False) -> None:
    """The FMU reference, one page per FMU (its text in ``fmu_src/docs/``; its reference plot
    rerun only with ``plots``: it simulates a catalog system per FMU), the controller design
    and, with ``plots``, the replay of docs/replay.md (its plot and table: 20 s)."""
    from altfusion.docs import (
        fmu_index,
        fmu_page,
        fmu_reference,
        read_fmu_text,
        reference_plot,
    )
    from altfusion.physics.controller_design import design, report

    fmus = sorted(fmu_paths.values())
    write_if_changed(DOCS / "fmu_reference.md", fmu_reference(fmus))
    write_if_changed(DOCS / "fmus" / "README.md", fmu_index(fmus))
    for fmu in fmus:
        text = read_fmu_text(FMU_TEXTS / f"{fmu.stem}.md")
        png = DOCS / "fmus" / f"{fmu.stem}.png"
        if plots:
            print(f"wrote {reference_plot(text.reference, fmu_paths, png).relative_to(HERE)}")
        page = fmu_page(fmu, text, png.name if png.exists() else None)
        write_if_changed(DOCS / "fmus" / f"{fmu.stem}.md", page)
    write_if_changed(DOCS / "controller_design.md", report(design()))
    if plots:
        replay_docs(HERE / "tests" / "data" / "flightlogs" / "auterion_esc_status_log.ulg",
                    fmu_paths, DOCS / "replay_auterion.png", DOCS / "replay.md")
        print("wrote docs/replay_auterion.png, docs/replay.md")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true",
                        help="exit 1 if an FMU is missing or older than its sources")
    parser.add_argument("--force", action="store_true", help="rebuild every FMU")
    parser.add_argument("--plots", action="store_true",
                        help="rerun the reference plots of the FMU pages and the replay of "
                             "docs/replay.md (about 1 min)")
    args = parser.parse_args(argv)
    # The in-process core is compiled before anything here imports the estimators (the slave
    # scripts do), so that this process runs them compiled too.
    from altfusion.compile_core import CompileError, compile_core, outdated
    from altfusion.compiled import FOLDER

    late = [f"{(p / FOLDER).relative_to(HERE)}" for p in outdated(CORE)]
    if not args.check:
        try:
            for package in compile_core(CORE):
                print(f"compiled {(package / FOLDER).relative_to(HERE)}")
        except CompileError as error:
            print(f"error: {error}", file=sys.stderr)
            return 1
    from altfusion.fmi.shim import ShimBuildError, compile_shim

    scripts = slave_scripts()
    targets = {script: MODELS / f"{model_name(script)}.fmu" for script in scripts}
    if args.check:
        late += [f"models/{fmu.name}" for script, fmu in targets.items() if stale(script, fmu)]
        for name in late:
            print(f"out of date: {name}")
        return 1 if late else 0
    MODELS.mkdir(exist_ok=True)
    problems = []
    core = shim = None
    try:
        for script, fmu in targets.items():
            if args.force or stale(script, fmu):
                print(f"building models/{fmu.name}")
                core = core or stage_core()
                shim = shim or compile_shim(SHIM_BUILD)
                build_fmu(script, core=core, shim=shim)
            problems += [f"{fmu.name}: {p}" for p in validate_fmu(fmu)]
    except (CompileError, ShimBuildError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    if problems:
        print("\n".join(problems), file=sys.stderr)
        return 1
    fmu_paths = {fmu.stem: fmu for fmu in targets.values()}
    for path in build_systems(fmu_paths):
        print(f"wrote {path.relative_to(HERE)}")
    build_docs(fmu_paths, args.plots)
    print(f"{len(targets)} FMUs valid, systems written")
    return 0


if __name__ == "__main__":
    sys.exit(main())
