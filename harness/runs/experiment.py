"""An experiment bound to its FMU, the one run object of every command: the settings of
:mod:`harness.config` (defaults < experiment file < flags or Python arguments, each with its
origin) checked against the FMU that runs them -- the FMU opened once, parameters coerced to its
types (the solver checked once: an FMU without the parameter runs CVODE only), the initial state,
sampling and run options.  The command line (:mod:`harness.cli`) and the library's entry points
(``compare_windows``, ``chart``, ``run_target``) build it the same way.

Lives in the runs layer because it opens the FMU (:mod:`harness.fmu`); where the settings come
from and their specs are :mod:`harness.config`'s job.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from ..config import (Layered, RunSpec, SamplingSpec, SweepSpec, _number, default_fmu_path, load_toml, parse_modes,
                      solver_name)
from ..errors import HarnessInputError


@dataclass
class Experiment:
    """Everything a run needs, validated against the FMU.

    Build it with :meth:`from_sources`; ``params`` maps FMU variable names to values of the
    right type, ``state0`` is (u0, v0) at the first section time.
    """

    fmu_path: str
    model: Any  # harness.fmu.fmi.FmuModel
    params: dict[str, Any]
    state0: tuple[float, float]
    sampling: SamplingSpec
    run: RunSpec
    layers: Layered = field(repr=False)

    @classmethod
    def from_sources(
        cls,
        config: str | os.PathLike | None = None,
        overrides: Mapping[str, Mapping[str, Any]] | None = None,
        model: Any = None,
        source: str = "cli",
    ) -> "Experiment":
        """Defaults < TOML file ``config`` < ``overrides`` (CLI), validated.

        Parameters
        ----------
        config : path, optional
            Experiment file (TOML).
        overrides : mapping, optional
            ``{section: {key: value}}``; ``None`` values mean "not given".
        model : FmuModel, optional
            Already opened FMU (otherwise opened from ``fmu.path``).
        source : str
            Where ``overrides`` come from: ``"cli"`` (errors name the flags) or ``"api"`` (a
            Python caller: errors name its arguments).
        """
        from ..fmu.fmi import FmuModel, INITIAL_STATE

        from ..errors import ErrorCollector

        # every mistake of the file and the flags is reported at once (one run, not one per mistake)
        found = ErrorCollector()
        layers = Layered()
        if config is not None:
            found.check(layers.merge, load_toml(config), Path(config).name)
        if overrides:
            found.check(layers.merge, overrides, source)
        path = layers.get("fmu", "path") or default_fmu_path()
        if model is None:
            fallback = "fmu_path" if source == "api" else "--fmu"
            try:
                model = FmuModel(path, argument=layers.arg("fmu", "path") if layers.given("fmu", "path") else fallback)
            except HarnessInputError as exc:  # nothing below can be checked without the FMU
                found.add(exc)
                found.raise_if_any()
        params = _model_params(model, layers, found)
        state = []
        for key in INITIAL_STATE:
            given = layers.get("initial", key)
            if given is None:
                state.append(float(params.get(key, -1.0 if key == "u0" else 0.0)))
            else:
                state.append(found.check(_number, layers, "initial", key, default=0.0))
        for key in INITIAL_STATE:
            params.pop(key, None)  # the state travels separately
        sampling = found.check(SamplingSpec.from_layers, layers)
        run = found.check(RunSpec.from_layers, layers)
        # the [sweep] names and modes are checked with the rest; its grid later, by the budget
        # first (a huge --num must be refused before it is allocated)
        for key in ("param", "scan_param"):
            if ("sweep", key) in layers.origin and layers.get("sweep", key) is not None:
                found.check(model.check_settable, str(layers.get("sweep", key)), layers.arg("sweep", key))
        if ("sweep", "mode") in layers.origin:
            found.check(parse_modes, layers.get("sweep", "mode"), layers.arg("sweep", "mode"))
        found.raise_if_any()
        return cls(
            fmu_path=str(model.path),
            model=model,
            params=params,
            state0=(state[0], state[1]),
            sampling=sampling,
            run=run,
            layers=layers,
        )

    @classmethod
    def for_python(cls, fmu_path: str | os.PathLike | None = None, solver: str | None = None,
                   workers: int | None = None, progress: bool = False,
                   model: Mapping[str, Any] | None = None, backend: str | None = None,
                   scheduler: str | None = None) -> "Experiment":
        """The run of a library entry point called from Python (``compare_windows``, ``chart``,
        ``run_target``): the same defaults and checks as a command, errors naming the Python
        arguments (``fmu_path``, ``solver``, ``workers``, ``backend``, ``scheduler``)."""
        layer: dict[str, dict[str, Any]] = {"fmu": {"path": None if fmu_path is None else str(fmu_path)},
                                            "model": {**(model or {}), "solver": solver},
                                            "run": {"workers": workers, "progress": bool(progress), "backend": backend,
                                                    "scheduler": scheduler}}
        return cls.from_sources(None, layer, source="api")

    @property
    def solver(self) -> str:
        """The FMU's integrator by name (:data:`harness.config.SOLVERS`); CVODE on an FMU without
        the parameter."""
        from ..config import DEFAULT_SOLVER

        return solver_name(self.params.get("solver", DEFAULT_SOLVER))

    def given(self, section: str, key: str) -> bool:
        """Whether ``section.key`` was set by a file, a flag or a Python argument."""
        return self.layers.given(section, key)

    def sweep_spec(self) -> SweepSpec:
        """The ``[sweep]`` section, validated against this experiment's FMU."""
        return SweepSpec.from_layers(self.layers, self.model)

    def as_attrs(self) -> dict[str, Any]:
        """Flat record of every setting (for the results' attributes)."""
        out: dict[str, Any] = {"fmu_path": self.fmu_path}
        for name, value in self.params.items():
            out[f"model.{name}"] = value
        out["initial.u0"], out["initial.v0"] = self.state0
        for section in ("sampling", "run"):
            for key, value in self.layers.values[section].items():
                out[f"{section}.{key}"] = value
        return out


def _model_params(model: Any, layers: Layered, found: Any) -> dict[str, Any]:
    """The FMU's start values with the ``[model]`` layers' values coerced to its types; the solver
    checked here, once for every command (an FMU without the parameter runs CVODE only)."""
    from ..fmu.fmi import SOLVER_PARAMETER

    params = model.defaults()
    for name, value in layers.values["model"].items():
        origin = layers.origin.get(("model", name))
        arg = f"--set {name}" if origin == "cli" else layers.arg("model", name)
        if name == SOLVER_PARAMETER and origin in ("cli", "api"):
            arg = "--solver" if origin == "cli" else "solver"
        if name == SOLVER_PARAMETER and name not in model.variables:
            # an FMU without the parameter integrates with CVODE: that choice is a no-op
            if str(value).lower() in ("cvode", "0"):
                continue
            found.add(HarnessInputError(arg, f"{model.path.name} has no closed-form solver mode (no parameter "
                                        f"{SOLVER_PARAMETER!r}); it integrates with CVODE only"))
            continue
        try:
            params[name] = model.coerce(name, value, arg)
        except HarnessInputError as exc:
            found.add(exc)
    return params
