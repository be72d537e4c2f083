"""Build the pythonfmu twin ``ImpactOscillatorPy.fmu``.

Usage (from the repository root, with the project's virtual environment)::

    .venv/bin/python fmu_src/pytwin/build.py --out build/fmu/ImpactOscillatorPy.fmu

``scripts/setup.sh`` runs exactly this when the twin's sources changed.  The FMU bundles the
slave (``ImpactOscillatorPy.py``), the physics and its driver (``impact_twin_model.py`` and the
``twin_*.py`` files it gathers) and pythonfmu's own Python files; numpy and scikit-sundae must
be importable by the Python that runs the FMU (see README.md next to this file).  The model description, InitialUnknowns included, is written by
the slave class itself (``ImpactOscillatorPy.to_xml``); this script checks it afterwards with
fmpy's validator and fails the build if the validator reports a problem.
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import zipfile
from pathlib import Path
from xml.etree import ElementTree

HERE = Path(__file__).resolve().parent
SCRIPT = HERE / "ImpactOscillatorPy.py"
# twin_variables.py: generated from fmu_src/variables.py (fmu_src/generate_variables.py)
PROJECT_FILES = [HERE / name for name in ("impact_twin_model.py", "twin_rules.py",
                                          "twin_physics.py", "twin_cvode.py",
                                          "twin_variables.py")]
FRONT = HERE / "twin_export.c"
#: The C FMU's state table (which FMI call is allowed in which state), compiled into the front so
#: that the twin and the C FMU refuse the same calls from one table.
STATES = HERE.parent / "fmu_states.c"
FMI2_INCLUDE = HERE.parent / "include" / "fmi2"
LINUX_BINARY = "binaries/linux64/ImpactOscillatorPy.so"
PYTHONFMU_BINARY = "binaries/linux64/ImpactOscillatorPy_pythonfmu.so"


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
    if sys.platform.startswith("linux"):
        add_front(Path(written))
    problems = validate(Path(written))
    if problems:
        Path(written).unlink(missing_ok=True)
        raise RuntimeError("fmpy validation failed:\n  " + "\n  ".join(problems))
    Path(written).replace(out)
    return out


def python_runtime() -> str:
    """``resources/python_runtime.txt``: the Python this FMU runs with outside a Python process.

    ``libpython``: the shared library the front (``twin_export.c``) loads with RTLD_GLOBAL;
    ``home``: its installation (PYTHONHOME while pythonfmu starts the interpreter); ``version``;
    ``site``: site-packages holding numpy and scikit-sundae (the slave adds them to ``sys.path``
    when it cannot import those packages otherwise).
    """
    libdir = sysconfig.get_config_var("LIBDIR") or ""
    soname = sysconfig.get_config_var("INSTSONAME") or ""
    if not sysconfig.get_config_var("Py_ENABLE_SHARED"):
        raise RuntimeError("this Python has no shared libpython (built without --enable-shared): "
                           "a C host could not run the twin")
    site = [sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]]
    lines = [f"libpython={os.path.join(libdir, soname)}", f"home={sys.base_prefix}",
             f"version={sys.version_info.major}.{sys.version_info.minor}"]
    lines += [f"site={p}" for p in dict.fromkeys(site)]
    return "\n".join(lines) + "\n"


def variable_table(model_description: bytes) -> str:
    """C header ``twin_vars.h``: the front's variable table, from the FMU's modelDescription."""
    types = {"Real": "T_REAL", "Integer": "T_INTEGER", "Boolean": "T_BOOLEAN", "String": "T_STRING"}
    causalities = {"parameter": "C_PARAMETER", "calculatedParameter": "C_CALCULATED",
                   "input": "C_INPUT", "output": "C_OUTPUT"}
    rows = []
    for sv in ElementTree.fromstring(model_description).iter("ScalarVariable"):
        kind = next(el.tag for el in sv if el.tag in types)
        rows.append(
            f'    {{{sv.get("valueReference")}u, {types[kind]}, '
            f'{causalities.get(sv.get("causality", "local"), "C_OTHER")}, '
            f'{"V_TUNABLE" if sv.get("variability") == "tunable" else "V_OTHER"}, '
            f'"{sv.get("name")}"}},'
        )
    return ("/* generated by build.py from modelDescription.xml */\n"
            "static const struct { fmi2ValueReference vr; int type, causality, variability; "
            "const char *name; } TWIN_VARS[] = {\n" + "\n".join(rows) + "\n};\n")


def add_front(fmu: Path) -> None:
    """Put the state-keeping front (``twin_export.c`` with the C FMU's ``fmu_states.c``) in place
    of pythonfmu's linux64 binary.

    pythonfmu's binary moves to ``ImpactOscillatorPy_pythonfmu.so`` next to it (the front loads
    it), and ``resources/python_runtime.txt`` records this build's Python (see README.md).
    """
    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if not cc:
        raise RuntimeError("no C compiler (cc) to build the twin's front")
    with zipfile.ZipFile(fmu) as z:
        entries = {info.filename: z.read(info) for info in z.infolist()}
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "twin_vars.h").write_text(variable_table(entries["modelDescription.xml"]))
        lib = Path(tmp) / "front.so"
        # -z nodelete: pythonfmu's exit handler is registered through this library, which must
        # stay mapped until exit even if the host dlcloses it.
        cmd = [cc, "-O2", "-fPIC", "-shared", "-Wall", "-Wextra", "-Werror",
               "-I", tmp, "-I", str(FMI2_INCLUDE), "-I", str(STATES.parent), str(FRONT), str(STATES),
               "-o", str(lib), "-ldl", "-Wl,-z,nodelete"]
        run = subprocess.run(cmd, capture_output=True, text=True)
        if run.returncode:
            raise RuntimeError(f"compiling {FRONT.name} failed:\n{run.stderr}")
        entries[PYTHONFMU_BINARY] = entries[LINUX_BINARY]
        entries[LINUX_BINARY] = lib.read_bytes()
    entries["resources/python_runtime.txt"] = python_runtime().encode()
    tmp_fmu = fmu.with_name(fmu.name + ".front")
    with zipfile.ZipFile(tmp_fmu, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in entries.items():
            z.writestr(name, data)
    tmp_fmu.replace(fmu)


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
