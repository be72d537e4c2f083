"""Interrupted and killed runs: chains keep their
finished points and resume, `--mode both` is one loop, workers and temporary folders die with
the run.  Interruptions land at known points through the test hook, never after a sleep."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import psutil
import pytest
import xarray as xr

from harness import FmuModel, FmuSimulator, SamplingSpec, SweepSpec, run_sweep
from harness.config.defaults import SECTION_PHASE
from harness.dynamics.maps.sampling import sample_periods
from harness.runs.tasks import TEST_HOOK_ENV
from harness.io.tempdirs import PREFIX, remove_stale

pytestmark = pytest.mark.slow  # real processes interrupted and killed, then resumed

ROOT = Path(__file__).resolve().parents[2]
TMP = Path(os.environ.get("TMPDIR", "/tmp"))


def _wait_for(condition, what: str, limit: float = 120.0, proc: subprocess.Popen | None = None) -> None:
    """Wait until ``condition()`` holds (a state, not a duration: the limit only stops a hang).
    With ``proc``: fail at once, with its output, if it ends before the condition holds."""
    deadline = time.monotonic() + limit
    while not condition():
        if proc is not None and proc.poll() is not None and not condition():
            out, err = proc.communicate()
            raise AssertionError(f"the process ended (status {proc.returncode}) before {what}:\n{out}\n{err}")
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.02)


def _default_sigint() -> None:
    """Run in the child before exec: a suite started from a background job (or a CI runner that
    starts jobs so) hands its children SIGINT as SIG_IGN, and Python then installs no
    KeyboardInterrupt handler, so the CLI would never see the Ctrl-C this test sends."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _partial_rows(path: Path) -> int:
    try:
        with np.load(path) as data:
            return len(data["period"])
    except (OSError, ValueError, KeyError):
        return 0


def _tmp_dirs_of(procs: list[int | psutil.Process]) -> list[Path]:
    pids = [p.pid if isinstance(p, psutil.Process) else p for p in procs]
    return [p for pid in pids for p in TMP.glob(f"{PREFIX}{pid}-*")]


# -- the hysteresis loop ------------------------------------------------------------------
LOOP_PARAMS = {"nu": 0.196, "Omega": 7.368, "Gamma": 1000.0, "r": 0.9, "wall": 1}


def test_both_is_a_loop_down_starts_where_up_ended(model: FmuModel) -> None:
    """The down scan of `--mode both` started again from (u0, v0) at the top. Now its
    first point goes on from the up scan's last state: the clock runs on, and an independent
    restart of the FMU from the up scan's final sample reproduces the down scan's first point."""
    grid = np.linspace(-0.03, 0.03, 5)
    s = SamplingSpec(n_transient=60, n_samples=8)
    ds = run_sweep(model, SweepSpec("sigma", grid, ("both",)), params=LOOP_PARAMS, state0=(grid[0], 0.0),
                   sampling=s, backend="serial", progress=False)
    up_top = ds.sel(direction="up", sigma=grid[-1])
    down_top = ds.sel(direction="down", sigma=grid[-1])
    t_up_end = float(up_top["t"].values[-1])
    assert float(down_top["t"].values[0]) == t_up_end + s.n_transient + 1  # no restart at t = theta

    sim = FmuSimulator(model.source())
    sim.start({**model.defaults(), **LOOP_PARAMS, "sigma": grid[-1]}, t_up_end,
              (float(up_top["u"].values[-1]), float(up_top["v"].values[-1])))
    r = sample_periods(sim, s.n_transient, s.n_samples)
    np.testing.assert_allclose(down_top["u"].values, r.u, rtol=0, atol=1e-8)
    np.testing.assert_allclose(down_top["v"].values, r.v, rtol=0, atol=1e-7)
    # `up,down` stay two independent scans, the down one restarted from (u0, v0) at t = theta
    apart = run_sweep(model, SweepSpec("sigma", grid, ("up", "down")), params=LOOP_PARAMS, state0=(grid[0], 0.0),
                      sampling=s, backend="serial", progress=False)
    assert float(apart.sel(direction="down", sigma=grid[-1])["t"].values[0]) == s.n_transient + 1
    xr.testing.assert_equal(apart["u"].sel(direction="up"), ds["u"].sel(direction="up"))
    # and the loop is a hysteresis loop: below sigma = 0 up has no impacts, down keeps them
    # just below (how far down the impacting orbit survives is not the point here)
    hits = ds["impacts"].sum("sample")
    below = ds["sigma"] < 0
    assert hits.sel(direction="up").values[below.values].max() == 0
    assert hits.sel(direction="down").values[below.values].max() > 0


# -- a chain interrupted and resumed --------------------------------------------------------
def test_interrupted_loop_keeps_its_points_and_resumes(tmp_path: Path, model: FmuModel) -> None:
    """Ctrl-C in `--mode both` kept 0 points (a chain was one task) while the message said the
    finished points were kept.  The loop's worker blocks before point 5 (in the down half);
    once 5 points are on disk the CLI gets SIGINT: it says 5 are kept, and the rerun resumes
    the loop at point 5 from the stored state and matches an uninterrupted run."""
    out = tmp_path / "loop.nc"
    ckpt = tmp_path / "loop.nc.partial"
    release = tmp_path / "release"
    values = "-0.03,-0.01,0.01,0.03"
    cmd = [sys.executable, "-m", "harness", "sweep", "--values", values, "--mode", "both", "--u0", "-0.03",
           "--v0", "0", *[f"--set={k}={v}" for k, v in LOOP_PARAMS.items()], "--transient", "60", "--samples", "8",
           "--workers", "1", "--out", str(out), "--no-plot", "--no-progress"]
    env = {**os.environ, TEST_HOOK_ENV: f"both:5:block:{release}"}
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            preexec_fn=_default_sigint)
    try:
        _wait_for(lambda: Path(str(release) + ".reached").exists() and _partial_rows(ckpt / "both.partial.npz") == 5,
                  "the loop to stop before point 5 with 5 points stored", proc=proc)
        children = psutil.Process(proc.pid).children(recursive=True)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    _wait_for(lambda: _gone(children), "the worker and the resource tracker to exit", limit=60)
    assert _tmp_dirs_of([proc.pid, *children]) == []  # Ctrl-C leaves no extraction folder
    assert "interrupted: 5 of 8 points are kept" in err and "rerun the same command to resume" in err
    assert not out.exists()

    res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert "1 tasks computed, 0 resumed (5 points of unfinished chains resumed)" in res.stdout
    assert not ckpt.exists()
    grid = np.array([float(x) for x in values.split(",")])
    reference = run_sweep(model, SweepSpec("sigma", grid, ("both",)), params=LOOP_PARAMS, state0=(-0.03, 0.0),
                          sampling=SamplingSpec(theta=SECTION_PHASE, n_transient=60, n_samples=8),
                          backend="serial", progress=False)  # the command's section phase
    with xr.open_dataset(out) as resumed:
        for name in ("period", "orbit_impacts", "impacts", "t"):
            np.testing.assert_array_equal(resumed[name].values, reference[name].values, err_msg=name)
        # the resumed points restart the integrator from the stored state: equal to rounding
        np.testing.assert_allclose(resumed["u"].values, reference["u"].values, rtol=0, atol=1e-8)
        np.testing.assert_allclose(resumed["v"].values, reference["v"].values, rtol=0, atol=1e-7)


def test_interrupt_before_any_point_keeps_nothing_and_says_so(tmp_path: Path) -> None:
    out = tmp_path / "x.nc"
    res = subprocess.run([sys.executable, "-m", "harness", "sweep", "--values", "0.5,0.6", "--mode", "both",
                          "--transient", "5", "--samples", "3", "--backend", "serial", "--out", str(out), "--no-plot",
                          "--no-progress"], cwd=ROOT, capture_output=True, text=True, timeout=120,
                         env={**os.environ, TEST_HOOK_ENV: "both:0:interrupt"})
    assert res.returncode == 130
    assert "nothing kept" in res.stderr and "kept in" not in res.stderr
    assert not list(tmp_path.iterdir())


# -- workers and temporary folders die with the run ------------------------------------------
def _start_blocked_pool_sweep(tmp_path: Path) -> tuple[subprocess.Popen, list[psutil.Process]]:
    """A CLI sweep on 2 pool workers, one of them blocked inside a task by the hook."""
    release = tmp_path / "never"
    cmd = [sys.executable, "-m", "harness", "sweep", "--values", "0.5,0.6,0.7", "--mode", "fresh", "--transient", "5",
           "--samples", "3", "--workers", "2", "--out", str(tmp_path / "x.nc"), "--no-plot", "--no-progress"]
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, TEST_HOOK_ENV: f"fresh-p00002:0:block:{release}"})
    try:
        _wait_for(lambda: Path(str(release) + ".reached").exists(), "a worker to block inside its task", proc=proc)
        children = psutil.Process(proc.pid).children(recursive=True)
        assert len(children) >= 2  # the workers (and the resource tracker)
        _wait_for(lambda: len(_tmp_dirs_of(children)) >= 1, "the blocked worker's extraction folder")
    except BaseException:
        release.touch()  # unblock, then stop the run: a failed test leaves no process behind
        proc.terminate()
        proc.wait(timeout=60)
        raise
    return proc, children


def _gone(procs: list[psutil.Process]) -> bool:
    """All of ``procs`` ended (a zombie counts as ended; a process object, not a pid, so that a
    pid reused by another process on a busy machine is not taken for the old one)."""
    return not any(_alive(p) for p in procs)


def _alive(proc: psutil.Process) -> bool:
    try:
        return proc.is_running() and proc.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_workers_and_temp_folders_die_with_the_parent(tmp_path: Path, sig: signal.Signals) -> None:
    """After SIGKILL of the main process the pool workers and the resource tracker lived on as
    orphans for over 10 minutes, and the extraction folders stayed.  Now the workers get
    SIGTERM from the kernel (PR_SET_PDEATHSIG), remove their folders and exit."""
    proc, children = _start_blocked_pool_sweep(tmp_path)
    os.kill(proc.pid, sig)
    _, err = proc.communicate(timeout=60)
    _wait_for(lambda: _gone(children), "the workers and the resource tracker to exit", limit=60)
    assert _tmp_dirs_of([proc.pid, *children]) == []
    if sig == signal.SIGTERM:
        assert proc.returncode == 143 and "terminated" in err and "Traceback" not in err
    else:
        assert proc.returncode == -signal.SIGKILL


def test_stale_folders_of_dead_processes_are_swept(tmp_path: Path) -> None:
    """A SIGKILLed process cannot clean up after itself: the next run removes folders whose
    owner pid is gone, and nothing else."""
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    dead_pid = int(dead.stdout)
    assert not psutil.pid_exists(dead_pid)
    stale = tmp_path / f"{PREFIX}{dead_pid}-abc123"
    live = tmp_path / f"{PREFIX}{os.getppid()}-def456"
    mine = tmp_path / f"{PREFIX}{os.getpid()}-ghi789"
    legacy = tmp_path / f"{PREFIX}jkl012"  # no pid in the name: not ours to judge
    for d in (stale, live, mine, legacy):
        (d / "sub").mkdir(parents=True)
    assert remove_stale(tmp_path) == [stale]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(d.name for d in (live, mine, legacy))


def test_folder_of_a_killed_serial_run_is_swept_by_the_next_run(tmp_path: Path) -> None:
    """A SIGKILLed process keeps its extraction folder (nothing can run in it); the next
    run of the harness removes it."""
    release = tmp_path / "never"
    proc = subprocess.Popen([sys.executable, "-m", "harness", "sweep", "--values", "0.5", "--mode", "fresh",
                             "--transient", "5", "--samples", "3", "--backend", "serial", "--out", str(tmp_path / "x.nc"),
                             "--no-plot", "--no-progress"], cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env={**os.environ, TEST_HOOK_ENV: f"fresh-p00000:0:block:{release}"})
    try:
        _wait_for(lambda: Path(str(release) + ".reached").exists(), "the run to block inside its task", proc=proc)
    finally:
        proc.kill()
    proc.wait(timeout=60)
    left = _tmp_dirs_of([proc.pid])
    assert len(left) == 1 and (left[0] / "").is_dir()
    res = subprocess.run([sys.executable, "-m", "harness", "strobe", "--transient", "2", "--samples", "2",
                          "--out", str(tmp_path / "s.nc"), "--no-plot", "--no-progress"],
                         cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert not left[0].exists()


def _child_goes_with_its_killed_parent(tmp_path: Path, source: str, what: str) -> None:
    """Run ``source`` as a script that prints its child's pid and holds it; SIGKILL the script;
    the child must exit (``what`` names it in a timeout).  A failed check leaves no process."""
    script = tmp_path / "parent.py"
    script.write_text(source)
    proc = subprocess.Popen([sys.executable, str(script)], cwd=ROOT, stdout=subprocess.PIPE, text=True)
    child = None
    try:
        child = psutil.Process(int(proc.stdout.readline()))
        assert _alive(child)
        proc.kill()
        proc.wait(timeout=60)
        _wait_for(lambda: _gone([child]), what, limit=60)
    finally:
        proc.kill()
        if child is not None and _alive(child):
            child.kill()


def test_other_pools_of_the_harness_die_with_their_parent(tmp_path: Path) -> None:
    """The parallel shooting's pool uses init_child_process: its workers go with a SIGKILLed
    parent too."""
    _child_goes_with_its_killed_parent(tmp_path, (
        "import multiprocessing, os, time\n"
        "from concurrent.futures import ProcessPoolExecutor\n"
        "from harness.io.children import init_child_process\n"
        "if __name__ == '__main__':\n"
        "    ctx = multiprocessing.get_context('spawn')\n"
        "    pool = ProcessPoolExecutor(1, mp_context=ctx, initializer=init_child_process, initargs=(os.getpid(),))\n"
        "    print(pool.submit(os.getpid).result(), flush=True)\n"
        "    time.sleep(600)  # hold the pool until killed\n"), "the pool worker to exit")


def test_a_worker_that_misses_the_death_signal_still_goes(tmp_path: Path) -> None:
    """The death signal can come too late to be handled (the kernel closes the dead parent's
    pipes first, and a worker already finalizing runs no Python handler): the watchdog thread
    sees the parent gone and ends the worker without it.  Here the worker ignores SIGTERM."""
    _child_goes_with_its_killed_parent(tmp_path, (
        "import multiprocessing, os, signal, time\n"
        "from harness.io.children import die_with_parent\n"
        "def child(parent):\n"
        "    die_with_parent(parent)\n"
        "    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # the signal is lost\n"
        "    print(os.getpid(), flush=True)\n"
        "    time.sleep(600)\n"
        "if __name__ == '__main__':\n"
        "    ctx = multiprocessing.get_context('spawn')\n"
        "    ctx.Process(target=child, args=(os.getpid(),)).start()\n"
        "    time.sleep(600)  # hold the child until killed\n"), "the worker to exit without its death signal")
