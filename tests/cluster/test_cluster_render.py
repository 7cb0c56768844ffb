"""Rendering on Ray (a local instance of 2 CPUs, started once for the module) gives the
one-process image bit for bit: for any number of tasks in flight and chunk size, after a worker
is killed mid-task, and after a stop and a resume with or without the cluster."""
from __future__ import annotations

import os
import shutil
import signal
import time
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
import pytest

ray = pytest.importorskip("ray")

import renderer  # noqa: E402
from cluster_scenes import write_cluster_scene  # noqa: E402
from renderer.api import settings_for  # noqa: E402
from renderer.cli import main  # noqa: E402
from renderer.cluster import Cluster, open_cluster  # noqa: E402
from renderer.errors import RenderError  # noqa: E402
from renderer.io.images import read_exr  # noqa: E402
from renderer.session import RenderSession  # noqa: E402

SPP = 6


@pytest.fixture(scope="module")
def local_ray():
    """Two worker CPUs; the dashboard serves the state API the kill test finds pids with (task
    events reported every 0.1 s instead of 1 s, so a running task shows up quickly)."""
    os.environ.setdefault("RAY_task_events_report_interval_ms", "100")
    ray.init(num_cpus=2, include_dashboard=True, log_to_driver=False,
             runtime_env={"env_vars": {"WARP_CACHE_PATH": os.environ["WARP_CACHE_PATH"]}})
    yield ray
    ray.shutdown()


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    return write_cluster_scene(tmp_path_factory.mktemp("cluster"))


def one_process(scene_file, seed: int) -> np.ndarray:
    return renderer.render(renderer.load_scene(scene_file), spp=SPP, seed=seed)


@pytest.fixture(scope="module")
def reference(scene_file):
    return one_process(scene_file, 5)


def test_workers_read_shipped_files_not_the_scene_folder(local_ray, tmp_path):
    """The scene folder is gone before the first task runs: the workers use the shipped bytes."""
    path = write_cluster_scene(tmp_path)
    expected = one_process(path, 8)
    scene = renderer.load_scene(path)
    render = open_cluster(scene, settings_for(scene, seed=8), Cluster(workers=2, chunk=3))
    shutil.rmtree(tmp_path / "maps")
    render.run(SPP)
    np.testing.assert_array_equal(render.image(), expected)


@pytest.mark.parametrize("workers, chunk", [(1, SPP), (2, 1), (3, 2), (2, 4), (3, None)])
def test_cluster_equals_one_process_bit_for_bit(local_ray, scene_file, reference, workers, chunk):
    img = renderer.render(renderer.load_scene(scene_file), spp=SPP, cluster=Cluster(workers=workers, chunk=chunk))
    assert img.shape == (16, 24, 3) and img.mean() > 0.05
    np.testing.assert_array_equal(img, reference)


def _tasks() -> list:
    """Every task of this test's Ray instance (named by its address: another instance on the same
    machine, say a second test run, would make Ray's own lookup refuse to choose)."""
    from ray.util.state import list_tasks

    return list_tasks(address=ray.get_runtime_context().gcs_address, detail=True, limit=10_000)


def _kill_a_running_task(render: Future) -> tuple[int, str]:
    """Kill (SIGKILL) the worker process of the first render task seen running; its pid and task id."""
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not render.done():
        running = [t for t in _tasks()
                   if t.func_or_class_name == "render_range" and t.state == "RUNNING" and t.worker_pid]
        if running:
            os.kill(running[0].worker_pid, signal.SIGKILL)
            return running[0].worker_pid, running[0].task_id
        time.sleep(0.05)
    render.result()                         # the render's own error, if it failed
    raise AssertionError("no render task was seen running")


def test_a_killed_worker_costs_only_its_task(local_ray, scene_file):
    """Two tasks of 160 spp at 96x64 run for seconds; one worker is killed mid-task, its task is
    retried and the image is still the one-process image."""
    scene = renderer.load_scene(scene_file)
    settings = settings_for(scene, width=96, height=64)
    whole = RenderSession(scene, settings)
    whole.run(320)
    render = open_cluster(scene, settings, Cluster(workers=2, chunk=160))
    with ThreadPoolExecutor(1) as pool:
        running = pool.submit(render.run, 320)
        pid, task = _kill_a_running_task(running)
        running.result(timeout=240)
    attempts = [t.attempt_number for t in _tasks() if t.task_id == task]
    assert max(attempts) >= 1, f"the task of killed worker {pid} was not retried: attempts {attempts}"
    assert render.film.spp == 320
    np.testing.assert_array_equal(render.image(), whole.image())


def test_stopped_cluster_render_resumes_with_or_without_the_cluster(local_ray, scene_file, reference):
    """A stop request (what Ctrl-C sets) after the first finished task keeps only finished
    ranges, possibly with holes; both a cluster and a one-process resume complete it exactly."""
    scene = renderer.load_scene(scene_file)
    settings = settings_for(scene)
    first = open_cluster(scene, settings, Cluster(workers=2, chunk=2))
    stats = first.run(SPP, should_stop=lambda: first.film.spp > 0)
    assert stats.interrupted and 0 < first.film.spp < SPP
    state = first.state()
    again = open_cluster(scene, settings, Cluster(workers=3, chunk=1))
    again.restore(state)
    again.run(SPP)
    np.testing.assert_array_equal(again.image(), reference)
    alone = RenderSession(scene, settings)
    alone.restore(state)
    alone.run(SPP)
    np.testing.assert_array_equal(alone.image(), reference)
    assert alone.stats.rays == again.stats.rays
    started = RenderSession(scene, settings)       # and a one-process checkpoint continued on the cluster
    started.run(2)
    onto = open_cluster(scene, settings, Cluster(workers=2, chunk=3))
    onto.restore(started.state())
    onto.run(SPP)
    np.testing.assert_array_equal(onto.image(), reference)


def test_time_limit_stops_handing_out_tasks(local_ray, scene_file):
    """Past the time limit no task is handed out; the first round (two 1-spp tasks) still runs."""
    scene = renderer.load_scene(scene_file)
    render = open_cluster(scene, settings_for(scene), Cluster(workers=2, chunk=1))
    stats = render.run(100, time_limit=0.0)
    assert stats.spp == 2 and render.ranges == [(0, 2)] and not stats.interrupted


def test_cli_ray_checkpoint_and_resume(local_ray, scene_file, reference, tmp_path, capsys):
    """``--ray`` with a checkpoint, then ``--resume`` of it to more samples with an AOV layer."""
    out, ck = tmp_path / "out.exr", tmp_path / "ck.npz"
    args = [str(scene_file), "-o", str(out), "--ray", "--ray-workers", "2", "--ray-chunk", "2", "--quiet"]
    assert main([*args, "--spp", "4", "--checkpoint", str(ck)]) == 0
    assert main([*args, "--spp", str(SPP), "--resume", str(ck), "--aov", "albedo"]) == 0   # AOVs: one local pass
    err = capsys.readouterr().err
    assert "worker " in err and "M samples/s" in err
    chans = read_exr(out)[0]
    assert 0.0 < chans["albedo.R"].mean() <= 1.0
    np.testing.assert_array_equal(np.stack([chans[c] for c in "RGB"], axis=-1), reference)


def test_a_failing_worker_is_reported_clearly(local_ray, tmp_path, capsys):
    """An environment image that only a worker's upload reads, and cannot: exit 2 naming the
    samples and the worker's own error (no retries: a task's error is not a lost worker)."""
    scene = write_cluster_scene(tmp_path)
    (tmp_path / "maps" / "sky.exr").write_bytes(b"not an image")
    assert main([str(scene), "-o", str(tmp_path / "o.exr"), "--ray", "--ray-workers", "1", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "a worker failed on samples 0..0" in err and str(tmp_path / "maps" / "sky.exr") in err   # not its copy


def test_gpu_tasks_on_a_cluster_without_gpus_are_refused(local_ray, scene_file):
    scene = renderer.load_scene(scene_file)
    with pytest.raises(RenderError, match="has 0 GPUs"):
        open_cluster(scene, settings_for(scene), Cluster(task_gpus=1))
