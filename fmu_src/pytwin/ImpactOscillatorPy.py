"""pythonfmu slave: the Python twin of the C FMU ``ImpactOscillator`` (FMI 2.0 Co-Simulation).

Same variables (names, value references, causalities, variabilities, start values) as
``fmu_src/modelDescription.xml``, so that the harness drives either FMU unchanged.  The physics
and the CVODE driver live in ``twin_physics.py`` and ``twin_cvode.py``, gathered by
``impact_twin_model.py`` (all bundled into the FMU's resources); this file is only the FMI face.

Error reporting: pythonfmu turns *any* Python exception raised in a callback into
``fmi2Fatal`` (``PySlaveInstance::handle_py_exception`` throws ``cppfmu::FatalError``); it has
no way to return ``fmi2Error``.  The twin therefore logs a clear message with status
``fmi2Error`` first (through the importer's logger when logging is on, and on stderr), then
raises, so a rejected parameter stops the importer as the C FMU's ``fmi2Error`` does, with the
same wording; and it keeps the instance usable afterwards (see ``ImpactOscillatorPy._reject``).

Build with ``python fmu_src/pytwin/build.py --out build/fmu/ImpactOscillatorPy.fmu``.
"""
from __future__ import annotations

import atexit
import ctypes
import math
import os
import sys
from pathlib import Path
from typing import Any, Optional
from xml.etree.ElementTree import Element, SubElement



def _use_build_site_packages() -> None:
    """Make numpy and scikit-sundae importable in a host that has no Python environment.

    In a C host the interpreter pythonfmu starts has only its standard library.  build.py
    records the site-packages of the Python that built the FMU in ``python_runtime.txt`` (next
    to this file in the FMU's resources); they are appended to ``sys.path`` only when the
    packages are not importable already, so a Python importer keeps its own.
    """
    import importlib.util

    if all(importlib.util.find_spec(m) is not None for m in ("numpy", "sksundae")):
        return
    record = Path(__file__).resolve().parent / "python_runtime.txt"
    if not record.is_file():
        return
    for line in record.read_text().splitlines():
        key, _, value = line.partition("=")
        if key == "site" and value not in sys.path and Path(value).is_dir():
            sys.path.append(value)


_use_build_site_packages()

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Initial, Fmi2Status
from pythonfmu.variables import Boolean, Integer, Real

from impact_twin_model import MODE_FREE, CvodeDriver, ModelError, OscillatorModel
# generated from fmu_src/variables.py (fmu_src/generate_variables.py), as the C FMU's declarations
from twin_variables import INITIAL_UNKNOWNS, VARIABLES

#: pythonfmu's variable classes by the FMI type names of twin_variables.VARIABLES
_TYPES = {"Real": Real, "Integer": Integer, "Boolean": Boolean}


#: Binaries of this FMU whose exit-time clean-up is already arranged (one per loaded copy).
_EXIT_GUARDED: set[str] = set()


def _guard_pythonfmu_exit(resources: Optional[str]) -> None:
    """Work around a use-after-free in pythonfmu 0.7's binary at process exit.

    The binary keeps a global ``std::shared_ptr<PyState>``; C++ static destruction frees it at
    exit, and then the library's ``__attribute__((destructor))`` (``onLibraryUnload`` ->
    ``finalizePythonInterpreter``) assigns to it again, writing into freed heap memory
    (valgrind: "Invalid read ... in finalizePythonInterpreter", a block freed by
    ``__run_exit_handlers``).  The library is never unloaded before exit (13 STB_GNU_UNIQUE
    symbols make it undeletable; it stays mapped after fmi2FreeInstance and dlclose), so every
    Python process that instantiated the FMU does this; in our pytest runs about one process in
    fifteen to twenty aborted at exit ("corrupted double-linked list", exit status 134).

    The cure is to call the exported ``finalizePythonInterpreter`` once *before* the C++
    destructors run: it empties the global, so both later steps see an empty pointer.

    - Python importer (``sys.orig_argv`` non-empty): from a Python ``atexit`` handler (Python
      finalises before the C exit handlers run).
    - C/C++ importer (pythonfmu started the interpreter, ``sys.orig_argv`` empty; the same
      abort, about one run in sixty with fmusim): Python code must not finalise the interpreter
      it runs in, so the C function itself is registered as a C exit handler (``__cxa_atexit``).  C exit
      handlers run in reverse order of registration, and this one is registered at the first
      ``fmi2Instantiate``, after the library's static shared_ptr was constructed, so it runs
      before that object's destructor: the interpreter is finalised (on pythonfmu's own
      thread, as in a normal unload) and the pointer emptied while its memory is still valid.
      The binary is never unloaded (above), so the function pointer stays valid until exit.

    Parameters
    ----------
    resources : str or None
        The FMU's unpacked ``resources`` folder (pythonfmu's ``resources`` argument).
    """
    if not (sys.platform.startswith("linux") and resources):
        return
    lib = str(Path(resources).resolve().parent / "binaries" / "linux64" / "ImpactOscillatorPy.so")
    if lib in _EXIT_GUARDED:
        return
    _EXIT_GUARDED.add(lib)

    if not getattr(sys, "orig_argv", None):  # a C/C++ importer: libc's atexit, see above
        try:
            fmu = ctypes.CDLL(lib, mode=os.RTLD_NOLOAD | os.RTLD_NOW)
            # glibc exports no dynamic "atexit" (it is a static stub in libc_nonshared.a
            # around __cxa_atexit); register with __cxa_atexit, no argument and no DSO (run
            # at exit).  The extra argument it passes is ignored by a function of no arguments.
            libc = ctypes.CDLL(None)
            libc.__cxa_atexit.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
            libc.__cxa_atexit(ctypes.cast(fmu.finalizePythonInterpreter, ctypes.c_void_p),
                              None, None)
        except (OSError, AttributeError):
            pass
        return

    def release() -> None:
        try:  # RTLD_NOLOAD: only the copy that is loaded, never a fresh one at exit
            ctypes.CDLL(lib, mode=os.RTLD_NOLOAD | os.RTLD_NOW).finalizePythonInterpreter()
        except (OSError, AttributeError):
            pass

    atexit.register(release)


class ImpactOscillatorPy(Fmi2Slave):
    """Driven oscillator with a rigid or compliant wall; CVODE (scikit-sundae) inside.

    Without the C FMU's ports (F_ext, u_wall in; F_contact, v_impact, t_impact out): pythonfmu
    assigns value references by registration order without gaps and has no input derivatives,
    so the shared value references 23-27 cannot be reproduced (README.md here).
    """

    author = "impact-grazing project"
    description = (
        "Python twin (pythonfmu, CVODE via scikit-sundae) of ImpactOscillator: periodically "
        "driven harmonic oscillator with a rigid or compliant wall (Molenaar, de Weger and van "
        "de Water, Nonlinearity 14 (2001) 301); wall crossings located by CVODE root finding"
    )
    default_experiment = DefaultExperiment(start_time=0.0, stop_time=100.0, step_size=1.0)
    #: The C FMU's log categories (pythonfmu's defaults name one per status instead).  pythonfmu
    #: 0.7 forwards a message only while the importer has logging on (and the category is
    #: among those it asked for), so per-step "logEvents" messages cost nothing otherwise.
    log_categories = {
        "logStatusError": "errors: bad parameters, calls in the wrong state, solver failures",
        "logEvents": "wall events per step, and those recovered by the rescue of a stepped-over crossing",
    }

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        _guard_pythonfmu_exit(self.resources)
        self.model = OscillatorModel()
        self.driver: Optional[CvodeDriver] = None
        self.start_time = 0.0
        self.initialized = False
        self.failed = False  # a doStep failed: only fmi2Reset helps (the C FMU's error state)
        # The order of registration is the value reference: VARIABLES is in the C FMU's order.
        for name, type_, causality, variability, initial, desc, _ in VARIABLES:
            getter, setter = self._accessors(name, causality)
            self.register_variable(
                _TYPES[type_](
                    name,
                    causality=Fmi2Causality[causality],
                    variability=Fmi2Variability[variability],
                    initial=Fmi2Initial[initial],
                    description=desc,
                    getter=getter,
                    setter=setter,
                )
            )

    # -- registration helpers --------------------------------------------------------------
    def _accessors(self, name: str, causality: str) -> tuple[Any, Any]:
        """The getter and setter (None: read-only) of the variable ``name``."""
        if name == "wall":
            return (lambda: self.model.wall), self._set_wall
        if causality == "parameter":
            return (lambda: getattr(self.model, name)), (lambda x: self._set_real(name, x))
        if name in ("u", "v"):
            # before initialisation the state is the start value (u0, v0)
            return (lambda: getattr(self.model, name if self.initialized else name + "0")), None
        if name == "in_contact":
            return (lambda: self.model.mode != MODE_FREE), None
        return (lambda: getattr(self.model, name)), None

    def _vr(self, name: str) -> int:
        """Value reference of a registered variable (for messages)."""
        return next(vr for vr, var in self.vars.items() if var.name == name)

    def _reject(self, message: str) -> None:
        """Log ``message`` as fmi2Error, then raise (pythonfmu returns fmi2Fatal).

        Every exception leaving a callback must come through here.  pythonfmu's exception
        handler (``handle_py_exception`` -> ``cleanPyObject``) releases one reference to this
        instance, to its class and to its log queue but keeps using the pointers: a later call,
        ``fmi2Reset`` (the harness reuses instances) or ``fmi2FreeInstance`` would then work on
        freed objects and crash the importer.  One reference to each, donated here to that
        clean-up (taken with ``Py_IncRef`` and owned by nobody on the Python side), keeps the
        counts balanced, so the instance survives a rejected parameter as the C FMU's does.
        """
        # The FMU's C front (twin_export.c) keeps pythonfmu's logging on and forwards every
        # error to the importer's logger, whatever the importer's logging setting.
        self.log(message, Fmi2Status.error, "logStatusError")
        for obj in (self, type(self), self.log_queue):
            ctypes.pythonapi.Py_IncRef(ctypes.py_object(obj))
        raise ModelError(message)

    def _set_real(self, name: str, x: float) -> None:
        if self.initialized and name != "sigma":
            self._reject(
                f"fmi2SetReal: {name} (value reference {self._vr(name)}) cannot be set now: "
                "only sigma is tunable after initialisation"
            )
        try:
            self.model.set_real(name, x)
        except ModelError as exc:
            self._reject(f"fmi2SetReal: {exc} (value kept at its previous setting)")
        if self.initialized and self.driver is not None:
            # a new sigma changes the right-hand side from now on: CVODE restarts here
            self.driver.needs_reinit = True

    def _set_wall(self, x: int) -> None:
        if self.initialized:
            self._reject(
                f"fmi2SetInteger: wall (value reference {self._vr('wall')}) cannot be set now: "
                "only sigma is tunable after initialisation"
            )
        try:
            self.model.set_wall(x)
        except ModelError as exc:
            self._reject(f"fmi2SetInteger: {exc}")

    # -- model description -----------------------------------------------------------------
    def to_xml(self, model_options: dict[str, str] = dict()) -> Element:  # noqa: B006
        """pythonfmu's model description, completed to match the C FMU's.

        Adds what pythonfmu cannot declare: ``providesDirectionalDerivative`` (answered by the C
        front), ``InitialUnknowns`` (required by FMI 2.0 for
        outputs with initial="calculated" and for calculated parameters), min/max and the
        ``rad`` unit on the variables, and the flat naming convention of the C FMU.
        """
        root = super().to_xml(model_options)
        root.set("variableNamingConvention", "flat")
        # the C front answers fmi2GetDirectionalDerivative (pytwin/twin_export.c)
        root.find("CoSimulation").set("providesDirectionalDerivative", "true")
        declared = {name: (type_, attrs) for name, type_, *_, attrs in VARIABLES}
        for sv in root.iter("ScalarVariable"):
            type_, attrs = declared[sv.get("name")]
            sv.find(type_).attrib.update(attrs)
        # UnitDefinitions must precede LogCategories (FMI 2.0 schema order).
        units = Element("UnitDefinitions")
        SubElement(units, "Unit", {"name": "rad"})
        children = list(root)
        pos = next(i for i, el in enumerate(children) if el.tag == "CoSimulation") + 1
        root.insert(pos, units)
        structure = root.find("ModelStructure")
        initial = SubElement(structure, "InitialUnknowns")
        for index, deps in INITIAL_UNKNOWNS:
            SubElement(initial, "Unknown", {"index": str(index), "dependencies": deps})
        return root

    # -- FMU state (fmi2GetFMUstate / fmi2SetFMUstate / serialisation) ----------------------
    _STATE_MAGIC = "ImpactOscillatorPy-state-1"
    _MODEL_FIELDS = ("nu", "Omega", "sigma", "r", "Gamma", "wall", "u0", "v0", "rtol", "atol",
                     "u", "v", "mode", "impacts")

    def _get_fmu_state(self) -> dict[str, Any]:
        """Snapshot: parameters, state, wall mode and time (a JSON-able dict, which pythonfmu
        serialises).  CVODE's step history is not part of it; as in the C FMU the live
        instance restarts CVODE here too, so "continue" and "restore, then continue" compute
        the very same numbers."""
        snap: dict[str, Any] = {"magic": self._STATE_MAGIC}
        snap.update({k: getattr(self.model, k) for k in self._MODEL_FIELDS})
        snap.update(start_time=self.start_time, initialized=self.initialized, failed=self.failed)
        if self.driver is not None:
            d = self.driver
            snap["driver"] = dict(origin=d.origin, tau=d.tau, events=d.events,
                                  guard_hits=d.guard_hits)
            d.needs_reinit = True
        else:
            snap["driver"] = None
        return snap

    def _set_fmu_state(self, state: dict[str, Any]) -> None:
        """Restore a snapshot of :meth:`_get_fmu_state` (CVODE restarts at its point)."""
        if not isinstance(state, dict) or state.get("magic") != self._STATE_MAGIC:
            self._reject("fmi2SetFMUstate: not a state of this FMU")
        for k in self._MODEL_FIELDS:
            setattr(self.model, k, state[k])
        self.model.update_derived()
        self.start_time = state["start_time"]
        self.initialized = state["initialized"]
        self.failed = state["failed"]
        snap = state["driver"]
        if snap is None:
            self.driver = None
            return
        try:
            # a new driver: the snapshot's rtol/atol may differ from the current CVODE's
            self.driver = CvodeDriver(self.model)
        except Exception as exc:
            self._reject(f"fmi2SetFMUstate: CVODE set-up failed: {exc!r}")
        self.driver.origin, self.driver.tau = snap["origin"], snap["tau"]
        self.driver.events, self.driver.guard_hits = snap["events"], snap["guard_hits"]
        self.driver.needs_reinit = True

    # -- FMI callbacks ---------------------------------------------------------------------
    def setup_experiment(
        self, start_time: float, stop_time: Optional[float] = None, tolerance: Optional[float] = None
    ) -> None:
        """Record the start time; the importer's tolerance tightens (never loosens) rtol."""
        if start_time is None or not math.isfinite(start_time):
            self._reject("fmi2SetupExperiment: startTime must be finite")
        self.start_time = float(start_time)
        if (
            tolerance is not None
            and math.isfinite(tolerance)
            and 0.0 < tolerance < self.model.rtol
        ):
            self.model.rtol = float(tolerance)

    def exit_initialization_mode(self) -> None:
        """Check the parameters together, set the initial mode and create CVODE."""
        try:
            self.model.check_all()
        except ModelError as exc:
            self._reject(f"fmi2ExitInitializationMode: {exc}")
        self.model.update_derived()
        try:
            self.driver = CvodeDriver(self.model)
        except ImportError as exc:
            self._reject(
                "fmi2ExitInitializationMode: the Python running this FMU "
                f"({sys.version.split()[0]}, prefix {sys.prefix}) cannot import scikit-sundae "
                f"({exc}); see fmu_src/pytwin/README.md (PYTHONPATH)"
            )
        except Exception as exc:  # anything else must go through _reject too (see there)
            self._reject(f"fmi2ExitInitializationMode: CVODE set-up failed: {exc!r}")
        self.driver.start(self.start_time)
        self.model.initialize_state(self.driver.tau)
        self.initialized = True

    def do_step(self, current_time: float, step_size: float) -> bool:
        """Integrate from ``current_time`` to ``current_time + step_size``."""
        if self.driver is None:
            self._reject("fmi2DoStep: called before initialisation ended")
        if self.failed:
            self._reject("fmi2DoStep: an earlier step failed; reset the instance")
        if not (math.isfinite(current_time) and math.isfinite(step_size)) or step_size < 0.0:
            self._reject(f"fmi2DoStep: bad communication step (t = {current_time}, h = {step_size})")
        now = self.driver.time
        if abs(current_time - now) > 1e-9 * max(1.0, abs(now)):
            self._reject(
                f"fmi2DoStep: currentCommunicationPoint {current_time!r} differs from the FMU's "
                f"time {now!r}"
            )
        events_before, guard_before = self.driver.events, self.driver.guard_hits
        try:
            self.driver.advance(current_time + step_size)
        except Exception as exc:  # SolverError, or a bug: either way through _reject
            self.failed = True
            self._reject(f"fmi2DoStep: integration failed: {exc}")
        if self.driver.events != events_before:
            self.log(
                f"fmi2DoStep: {self.driver.events - events_before} wall events in "
                f"({current_time!r}, {current_time + step_size!r}], "
                f"{self.driver.guard_hits - guard_before} of them recovered by the rescue of a stepped-over crossing",
                Fmi2Status.ok,
                "logEvents",
            )
        return True
