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
        The name of the argument as the user wrote it (``"--theta"``, ``"sampling.theta"``,
        ``"theta"`` for the API), or the FMU variable concerned.
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
