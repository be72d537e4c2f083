"""Build the pythonfmu twin ``ImpactOscillatorPy.fmu``.

Usage (from the repository root, with the project's virtual environment)::

    .venv/bin/python fmu_src/pytwin/build.py --out build/fmu/ImpactOscillatorPy.fmu

``scripts/setup.sh`` runs exactly this when the twin's sources changed.  The FMU bundles the
slave (``ImpactOscillatorPy.py``), the physics (``impact_twin_model.py``) and pythonfmu's own Python
files; numpy and scikit-sundae must be importable by the Python that runs the FMU (see
README.md next to this file).  The model description, InitialUnknowns included, is written by
the slave class itself (``ImpactOscillatorPy.to_xml``); this script checks it afterwards with
fmpy's validator and fails the build if the validator reports a problem.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
SCRIPT = HERE / "ImpactOscillatorPy.py"
PROJECT_FILES = [HERE / "impact_twin_model.py"]


def build(out: Path) -> Path:
    """Build the FMU at ``out`` and validate its model description.

    Parameters
    ----------
    out : Path
        Destination ``.fmu`` file (parent folders are created).

    Returns
    -------
    Path
        The written FMU.

    Raises
    ------
    RuntimeError
        If fmpy's validation of the model description reports problems.
    """
    from pythonfmu.builder import FmuBuilder

    out = out.resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".tmp.fmu")
    # Build next to the target, then rename: an importer never sees a half-written FMU.
    written = FmuBuilder.build_FMU(
        SCRIPT,
        dest=tmp,
        project_files=PROJECT_FILES,
        # pythonfmu >= 0.6 defaults needsExecutionTool to true; the FMU only needs a Python
        # with the packages of README.md, not a tool, as the C FMU it is a plain shared library.
        needsExecutionTool=False,
        # the slave implements _get_fmu_state/_set_fmu_state (JSON-able snapshots)
        canGetAndSetFMUstate=True,
        canSerializeFMUstate=True,
    )
    problems = validate(Path(written))
    if problems:
        Path(written).unlink(missing_ok=True)
        raise RuntimeError("fmpy validation failed:\n  " + "\n  ".join(problems))
    Path(written).replace(out)
    return out


def validate(fmu: Path) -> list[str]:
    """Return fmpy's validation problems for the FMU's model description (empty: valid)."""
    from fmpy.validation import validate_fmu

    return list(validate_fmu(str(fmu)))


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point; returns the process exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("build/fmu/ImpactOscillatorPy.fmu"),
        help="FMU file to write (default: build/fmu/ImpactOscillatorPy.fmu)",
    )
    args = parser.parse_args(argv)
    try:
        path = build(args.out)
    except Exception as exc:  # report, not a traceback, from a build script
        print(f"build.py: {exc}", file=sys.stderr)
        return 1
    print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
