"""Builds across real processes: kill -9 and resume, and an external dask scheduler + workers."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from pipeline_testing import (FAKE, REPO, assert_matches_fake, fake_kind, finished_indices, load,
                              subprocess_env)
from snapmorph.pipeline.build import build_map
from snapmorph.pipeline.checkpoint import checkpoint_dir
from snapmorph.pipeline.compare import compare_maps
from snapmorph.pipeline import preset

from pipeline_testing import CI  # noqa: E402  (the three-axis CI grid of the fake solver)


def wait_for(predicate, timeout, what):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return
        time.sleep(0.05)
    raise TimeoutError(f"timed out after {timeout} s waiting for {what}")


def kill_group(proc, sig=signal.SIGKILL, timeout=15):
    """Kill the process group of a subprocess started with start_new_session=True."""
    try:
        os.killpg(proc.pid, sig)
    except ProcessLookupError:
        pass
    try:
        proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=timeout)


def group_alive(pgid):
    try:
        os.killpg(pgid, 0)
        return True
    except ProcessLookupError:
        return False


def cli_build(out, *extra):
    return [sys.executable, "-m", "snapmorph", "maps", "build", "--grid", "ci", "--out", str(out),
            "--solver", FAKE, "--no-progress", "--max-failed", "2",
            "--kind", "pipeline_testing:fake_kind", *extra]


def logged_points(log):
    coords = [tuple(p) for p in CI.points()]
    calls = [tuple(map(float, line.split())) for line in log.read_text().splitlines()] if log.exists() else []
    return [coords.index(c) for c in calls]


@pytest.mark.slow
def test_kill_9_and_resume(tmp_path):
    out = tmp_path / "ci.nc"
    log1, log2 = tmp_path / "run1.log", tmp_path / "run2.log"
    proc = subprocess.Popen(
        cli_build(out, "--workers", "2", "--batch-size", "2"), cwd=REPO, start_new_session=True,
        env=subprocess_env(FAKE_SOLVER_LOG=log1, FAKE_SOLVER_DELAY=0.15),
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    try:
        wait_for(lambda: len(list(checkpoint_dir(out).glob("batch-*.npz"))) >= 3 or proc.poll() is not None,
                 90, "three checkpointed batches")
        assert proc.poll() is None, proc.stdout.read().decode()
    finally:
        kill_group(proc)  # kill -9 the driver, its scheduler and its worker processes
    wait_for(lambda: not group_alive(proc.pid), 15, "the killed build's processes to exit")
    assert not out.exists()
    finished = finished_indices(out)
    assert 6 <= len(finished) < CI.size
    meta = json.loads((checkpoint_dir(out) / "build.json").read_text())

    r = subprocess.run(cli_build(out, "--workers", "2"), cwd=REPO, timeout=120,
                       env=subprocess_env(FAKE_SOLVER_LOG=log2), capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert f"resumed from checkpoint {len(finished)}" in r.stdout
    second = logged_points(log2)
    assert len(second) == len(set(second)) == CI.size - len(finished)
    assert set(second).isdisjoint(finished)  # nothing finished was recomputed
    assert set(second) | finished == set(range(CI.size))
    assert set(logged_points(log1)) >= finished

    reference = tmp_path / "reference.nc"
    build_map(CI, reference, kind=fake_kind(), solve=FAKE, workers=2, progress=False)
    resumed, expected = load(out), load(reference)
    assert compare_maps(expected, resumed, rtol=0, atol=0) == []
    assert out.read_bytes() == reference.read_bytes()  # the same file, byte for byte
    assert_matches_fake(resumed)
    # the map records the build's start (time, commit), not the restart's; the rest is equal
    # (the lead may commit while this runs, so the reference build's commit can differ)
    assert (resumed.attrs["created"], resumed.attrs["git_commit"]) == (meta["created"], meta["git_commit"])
    started = ("created", "git_commit")
    assert {k: v for k, v in resumed.attrs.items() if k not in started} == \
        {k: v for k, v in expected.attrs.items() if k not in started}
    assert not checkpoint_dir(out).exists()


@pytest.fixture
def external_cluster(tmp_path):
    """`dask scheduler` and `dask worker` (2 single-threaded processes) on 127.0.0.1."""
    sched_file = tmp_path / "scheduler.json"
    env = subprocess_env(FAKE_SOLVER_LOG=tmp_path / "external-workers.log")
    procs = []
    try:
        procs.append(subprocess.Popen(
            [sys.executable, "-m", "dask", "scheduler", "--host", "127.0.0.1", "--port", "0",
             "--no-dashboard", "--scheduler-file", str(sched_file)],
            env=env, cwd=tmp_path, start_new_session=True,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        wait_for(lambda: sched_file.exists() and sched_file.stat().st_size > 0, 60, "the scheduler file")
        time.sleep(0.1)
        address = json.loads(sched_file.read_text())["address"]
        procs.append(subprocess.Popen(
            [sys.executable, "-m", "dask", "worker", address, "--nworkers", "2", "--nthreads", "1",
             "--host", "127.0.0.1", "--no-dashboard", "--death-timeout", "60"],
            env=env, cwd=tmp_path, start_new_session=True,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        yield address
    finally:
        for p in reversed(procs):
            kill_group(p, signal.SIGTERM)


@pytest.mark.slow
def test_build_on_an_external_cluster(external_cluster, tmp_path, monkeypatch):
    out = tmp_path / "ci.nc"
    report = build_map(CI, out, kind=fake_kind(), solve=FAKE, scheduler=external_cluster, workers=2,
                       progress=False, timeout=60)
    assert report.workers == 2
    assert_matches_fake(load(out))
    worker_log = tmp_path / "external-workers.log"  # only the external workers log
    assert sorted(logged_points(worker_log)) == list(range(CI.size))
    # the same through DASK_SCHEDULER_ADDRESS and the CLI
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", external_cluster)
    r = subprocess.run(cli_build(tmp_path / "env.nc", "--workers", "2"), cwd=REPO, timeout=120,
                       env=subprocess_env(DASK_SCHEDULER_ADDRESS=external_cluster),
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "2 workers" in r.stdout
    assert sorted(logged_points(worker_log)) == sorted(list(range(CI.size)) * 2)
    assert compare_maps(load(out), load(tmp_path / "env.nc"), rtol=0, atol=0) == []
