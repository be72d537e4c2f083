"""A sweep through a real dask.distributed scheduler with two worker processes on loopback.

The scheduler and the workers are separate processes started with the ``dask`` command
(workers without a nanny, so that killing one really loses it).  The same sweep on the
local process pool is the reference: the Datasets must be identical, also when a worker is
killed while it computes.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.slow  # a real Dask scheduler and two worker processes on loopback, one of them killed
import xarray as xr

from harness import FmuModel, SamplingSpec, SweepSpec, run_sweep

distributed = pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[2]
FMU = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"
DASK = Path(sys.executable).with_name("dask")
DATA_VARS = ("u", "v", "impacts", "t", "period", "orbit_impacts")
SAMPLING = SamplingSpec(n_transient=300, n_samples=10)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory: pytest.TempPathFactory):
    """Scheduler + 2 single-threaded worker processes on 127.0.0.1; yields (client, workers).

    Shared by the tests of this module; the test that kills a worker comes last.
    """
    tmp_path = tmp_path_factory.mktemp("dask")
    sched_file = tmp_path / "scheduler.json"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    procs: list[subprocess.Popen] = []
    scheduler = subprocess.Popen(
        [str(DASK), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
         "--scheduler-file", str(sched_file)],
        cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )
    procs.append(scheduler)
    try:
        deadline = time.time() + 60
        while not sched_file.exists() and time.time() < deadline:
            time.sleep(0.1)
        address = json.loads(sched_file.read_text())["address"]
        workers = [
            subprocess.Popen(
                [str(DASK), "worker", address, "--nthreads", "1", "--no-nanny", "--no-dashboard",
                 "--host", "127.0.0.1", "--name", f"w{i}", "--local-directory", str(tmp_path / f"w{i}")],
                cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            )
            for i in range(2)
        ]
        procs.extend(workers)
        client = distributed.Client(address, timeout="30s")
        client.wait_for_workers(2, timeout=60)
        assert address.startswith("tcp://127.0.0.1:")
        yield client, workers
        client.close()
    finally:
        # Our own processes: workers are killed outright (a graceful close of a nanny-less
        # worker waits for timeouts), then the scheduler is asked to stop.
        for p in procs[1:]:
            if p.poll() is None:
                p.kill()
        scheduler.terminate()
        for p in procs:
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                p.kill()


def _assert_same(a: xr.Dataset, b: xr.Dataset) -> None:
    for name in DATA_VARS:
        xr.testing.assert_equal(a[name], b[name])


def test_cli_sweep_with_scheduler_address(model: FmuModel, cluster, tmp_path: Path) -> None:
    client, _ = cluster
    address = client.scheduler.address
    out = tmp_path / "d.nc"
    res = subprocess.run(
        [sys.executable, "-m", "harness", "sweep", "--scheduler", address, "--values", "0.4,0.9", "--mode", "fresh",
         "--transient", "300", "--samples", "6", "--out", str(out), "--no-plot", "--no-progress"],
        cwd=ROOT, capture_output=True, text=True, timeout=120,
    )
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        assert ds.attrs["backend"].startswith(f"dask (scheduler {address}")
        assert ds["period"].sel(direction="fresh").values.tolist() == [2, 1]


def test_batch_kernel_basins_on_dask_equal_the_local_scan(cluster, tmp_path: Path) -> None:
    """The batch kernel's tiles on the two workers: the same labels as in this process, and a
    rerun with the checkpoint computes nothing."""
    from harness.runs.basins.kernel_scan import run_basins_kernel
    from harness.runs.sweep_collect import SweepStats

    client, _ = cluster
    params = {"nu": 0.196, "Omega": 7.368, "r": 0.9, "Gamma": 1000.0, "wall": 1, "sigma": 0.01, "solver": 1}
    s = SamplingSpec(n_transient=150, n_samples=30)
    u0, v0 = np.linspace(-1.2, 0.0, 24), np.linspace(-8.0, 8.0, 20)
    local = run_basins_kernel(None, u0, v0, params, s, progress=False, tile_size=60)
    ckpt = tmp_path / "ckpt"
    remote = run_basins_kernel(None, u0, v0, params, s, progress=False, tile_size=60, backend=client,
                               checkpoint=str(ckpt))
    assert remote.attrs["backend"].startswith("batch kernel (closed form in C) on dask")
    np.testing.assert_array_equal(remote["attractor"].values, local["attractor"].values)
    stats = SweepStats()
    again = run_basins_kernel(None, u0, v0, params, s, progress=False, tile_size=60, backend=client,
                              checkpoint=str(ckpt), stats=stats)
    assert stats.computed == 0 and stats.resumed == 8
    np.testing.assert_array_equal(again["attractor"].values, local["attractor"].values)


def test_atlas_tiles_on_dask_equal_the_local_run(cluster, tmp_path: Path) -> None:
    """The atlas's tiles on the two workers: the same per-start results as in this process, and a
    rerun with the checkpoint computes nothing."""
    from harness.runs.atlas.plane import AtlasPlane
    from harness.runs.atlas.scan import run_atlas_plane

    client, _ = cluster
    params = {"nu": 4.605170185988091, "Omega": 0.3059238689620112, "r": 0.9, "Gamma": 10.0, "wall": 1}
    plane = AtlasPlane(params, "Gamma", np.geomspace(10, 300, 4), np.linspace(0.2, 1.1, 5), starts=3, theta=0.0)
    local = run_atlas_plane(plane, progress=False, tile_pixels=5)
    ckpt = tmp_path / "ckpt"
    remote = run_atlas_plane(plane, progress=False, tile_pixels=5, backend=client, checkpoint=str(ckpt))
    assert remote.describe.startswith("batch kernel (closed form in C) on dask")
    for k in local.data:
        np.testing.assert_array_equal(remote.data[k], local.data[k])
    again = run_atlas_plane(plane, progress=False, tile_pixels=5, backend=client, checkpoint=str(ckpt))
    assert again.resumed == again.tiles == 4


def test_dask_sweep_equals_local_and_survives_a_killed_worker(model: FmuModel, cluster) -> None:
    client, workers = cluster
    spec = SweepSpec("sigma", np.linspace(0.2, 1.0, 8), ("fresh", "up"))
    reference = run_sweep(model, spec, sampling=SAMPLING, backend="processes", workers=2, progress=False)

    via_dask = run_sweep(model, spec, sampling=SAMPLING, backend=client, progress=False)
    _assert_same(via_dask, reference)
    assert via_dask.attrs["backend"].startswith("dask (scheduler tcp://127.0.0.1:")

    # Second run: kill worker 0 while it computes a task; the scheduler reruns it elsewhere.
    pids = client.run(os.getpid)
    victim = workers[0]
    victim_address = next(a for a, pid in pids.items() if pid == victim.pid)
    seen_busy: list[str] = []

    def killer() -> None:
        deadline = time.time() + 60
        while time.time() < deadline:
            busy = client.processing().get(victim_address, [])
            if busy:
                seen_busy.extend(map(str, busy))
                time.sleep(0.2)  # well inside the task (each takes ~0.1-1 s)
                os.kill(victim.pid, signal.SIGKILL)
                return
            time.sleep(0.02)

    thread = threading.Thread(target=killer, daemon=True)
    thread.start()
    survived = run_sweep(model, spec, sampling=SAMPLING, backend=client, progress=False)
    thread.join(5)
    assert seen_busy, "the victim never got a task"
    assert victim.wait(10) == -signal.SIGKILL
    assert len(client.scheduler_info()["workers"]) == 1
    _assert_same(survived, reference)
