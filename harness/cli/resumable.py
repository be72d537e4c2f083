"""Running a sweep-like job from the command line so that nothing is lost: its checkpoint
(``OUT.partial`` unless ``--checkpoint`` says otherwise) is resumed by a rerun of the same
command, discarded with a note when it belongs to another run, and after Ctrl-C the user is
told what is kept on disk."""
from __future__ import annotations

import shutil
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

from ..errors import FmuRejectedInput, HarnessInputError

if TYPE_CHECKING:  # the CLI starts without importing xarray and Dask
    from ..runs.experiment import Experiment
    from ..runs.sweeps import SweepStats


def run_resumable(job: Callable[[str], Any], exp: Experiment, out: Path, stats: SweepStats,
                  no_resume: bool = False) -> tuple[Any, Path]:
    """Run ``job(checkpoint_dir)`` with the command line's checkpoint rules.

    Parameters
    ----------
    job : callable
        Runs the work with the given checkpoint directory and returns its result; it fills
        ``stats`` (kept and total points) as it goes.
    exp : Experiment
        For ``run.checkpoint`` and the name of its flag.
    out : Path
        The result file; the default checkpoint is ``OUT.partial`` beside it.
    stats : SweepStats
        The job's statistics (read after an interruption).
    no_resume : bool
        Discard an existing checkpoint first (``--no-resume``).

    Returns
    -------
    (result, checkpoint path)
        The caller removes the checkpoint once the result is written.
    """
    explicit = exp.run.checkpoint is not None
    ckpt = Path(exp.run.checkpoint) if explicit else out.with_name(out.name + ".partial")
    if no_resume and ckpt.exists():
        shutil.rmtree(ckpt)
    ckpt_is_new = not ckpt.exists()
    try:
        try:
            result = job(str(ckpt))
        except HarnessInputError as exc:
            from ..runs.checkpoint import CheckpointMismatch

            if explicit or not isinstance(exc, CheckpointMismatch):
                raise
            # The default checkpoint of an earlier, different run to the same file: start over,
            # saying what differs (the user may have meant to resume it).
            why = "; ".join(exc.changes) if exc.changes else "other parameters or FMU"
            print(f"note: discarding {ckpt}, the checkpoint of a different run ({why}); starting afresh",
                  file=sys.stderr)
            shutil.rmtree(ckpt)
            result = job(str(ckpt))
    except KeyboardInterrupt:
        # say what is really on disk: whole tasks and the leading points of chains
        if stats.kept_points:
            print(f"interrupted: {stats.kept_points} of {stats.total_points} points are kept in {ckpt}; "
                  "rerun the same command to resume", file=sys.stderr)
        else:
            print("interrupted before any point finished; nothing kept", file=sys.stderr)
            if ckpt_is_new:
                shutil.rmtree(ckpt, ignore_errors=True)
        raise
    except (HarnessInputError, FmuRejectedInput):
        # Rejected input: a rerun needs other settings, which could not resume this
        # checkpoint anyway; one made by this run goes (else the next run notes discarding it).
        if ckpt_is_new:
            shutil.rmtree(ckpt, ignore_errors=True)
        raise
    return result, ckpt
