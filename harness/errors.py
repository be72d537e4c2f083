"""Errors the harness raises for bad input.

Every user-facing check raises :class:`HarnessInputError`, which names the offending
argument and the reason.  The CLI turns it into a one-line message and exit status 2
(the same convention as :mod:`argparse`), never a traceback.
"""
from __future__ import annotations


class HarnessInputError(ValueError):
    """Bad input to the harness: names the argument and says why it is rejected.

    Parameters
    ----------
    argument : str
        The name of the argument as the caller wrote it: the Python argument in the library
        (``"p_range"``, ``"theta"``; :mod:`harness.cli.flags` turns it into the command's flag
        when the CLI prints the message), a flag where the CLI checks its own input
        (``"--theta"``), a key of the experiment file (``"sampling.theta"``), or the FMU
        variable concerned.
    reason : str
        Why the value is rejected, phrased to complete "argument <name>: ...".
    """

    def __init__(self, argument: str, reason: str) -> None:
        self.argument = argument
        self.reason = reason
        super().__init__(f"argument {argument}: {reason}")

    def __reduce__(self) -> tuple:
        # picklable with both fields: it may be raised in a worker process
        return (type(self), (self.argument, self.reason))


class FmuError(RuntimeError):
    """The FMU itself failed (an fmi2Status of Error or Fatal during a run)."""


class SweepTaskError(RuntimeError):
    """A sweep task failed on a worker for a reason other than bad input or the FMU
    (e.g. the package is missing on a Dask worker); names the task."""


class FmuRejectedInput(FmuError):
    """The FMU refused the settings at initialization (e.g. a start inside a rigid wall).

    Bad input, found by the FMU rather than by the harness: the CLI exits with status 2.
    """


class SettingsErrors(HarnessInputError):
    """Several bad settings, reported together (a config file with several mistakes is
    answered once, not one mistake per run).  :attr:`errors` holds each; the message has one
    line per error."""

    def __init__(self, errors: list[HarnessInputError]) -> None:
        self.errors = list(errors)
        super().__init__(self.errors[0].argument, self.errors[0].reason)

    def __str__(self) -> str:
        return f"{len(self.errors)} problems in the settings:\n  " + "\n  ".join(
            f"argument {e.argument}: {e.reason}" for e in self.errors)

    def __reduce__(self) -> tuple:
        return (type(self), (self.errors,))


class ErrorCollector:
    """Run checks, keep going past bad input, and raise everything found at the end.

    ``value = collector.check(func, *args)`` returns ``func``'s result, or ``default`` after
    recording its :class:`HarnessInputError`; :meth:`raise_if_any` raises the one error found,
    or :class:`SettingsErrors` with all of them.
    """

    def __init__(self) -> None:
        self.errors: list[HarnessInputError] = []

    def check(self, func, *args, default=None, **kwargs):  # noqa: ANN001, ANN002, ANN003, ANN201 (any check)
        try:
            return func(*args, **kwargs)
        except HarnessInputError as exc:
            self.add(exc)
            return default

    def add(self, exc: HarnessInputError) -> None:
        """Record ``exc`` (the errors of a :class:`SettingsErrors` one by one)."""
        self.errors.extend(exc.errors if isinstance(exc, SettingsErrors) else [exc])

    def raise_if_any(self) -> None:
        if len(self.errors) == 1:
            raise self.errors[0]
        if self.errors:
            raise SettingsErrors(self.errors)
