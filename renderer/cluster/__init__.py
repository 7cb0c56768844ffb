"""One render over many processes or machines, on Ray's task API (remote functions, ``ray.put``,
``ray.wait``, ``max_retries``); nothing here schedules, transports or talks to workers by itself.

The driver loads and builds the scene once, puts the :class:`SceneDescription` and the bytes of
every file its upload reads into Ray's object store (:mod:`.shipping`: workers need no shared file
system), and hands out contiguous ranges of sample indices as tasks (:mod:`.driver`). A task
(:mod:`.worker`) renders its range into an empty film on its worker's device, keeping the upload
between tasks, and returns the range's film sums; the driver adds them.

Same image as one machine, bit for bit, for any worker count, chunking and finishing order: a
sample's random numbers depend only on (seed, sample index, pixel, dimension), and films hold
exact fixed-point integer sums of the samples (:mod:`renderer.device.film`), in one process too.
Integer addition is associative, so no grouping or order of partial films changes a bit. The
other way, adding float64 chunk sums in sample order, would have forced the one-process film to
sum in the same fixed blocks, chunks to be multiples of them, and the driver to hold early
finishers until every range before them arrived; fixed point has none of those constraints.
Its cost, measured by ``benchmarks/cluster.py``: one small kernel per pass and row chunk that
moves each float32 sample into the integer sums (0.4-0.7% of a pass on the demo scene from 96x54
to 960x540), a device film of 72 instead of 24 bytes a pixel (the float64 sample scratch and two
int64 sums), and a round-down of each sample by under 2^-62: every scene's baseline image stayed
bit-identical.

Nothing lost: a task whose worker dies is retried by Ray (``TASK_RETRIES``); the driver checkpoints
the merged film with its finished ranges in the one-process format (:mod:`renderer.film_state`),
so ``--resume`` continues with or without a cluster."""
from __future__ import annotations

from pathlib import Path

from renderer.cluster.driver import Cluster, ClusterRender
from renderer.scene.description import SceneDescription
from renderer.settings import RenderSettings

__all__ = ["Cluster", "ClusterRender", "open_cluster"]


def open_cluster(scene: SceneDescription, settings: RenderSettings, cluster: Cluster | str | None,
                 device: str = "cpu", threads: int | None = None, resume: str | Path | None = None) -> ClusterRender:
    """A cluster render ready to ``run``; ``cluster`` may be a bare address. A CUDA ``device``
    gives each task one GPU unless ``cluster`` says otherwise; ``threads`` sets each task's CPUs;
    ``resume`` continues a checkpoint (of a cluster or a one-process render)."""
    from dataclasses import replace

    from renderer.io.checkpoint import load_checkpoint

    c = cluster if isinstance(cluster, Cluster) else Cluster(address=cluster)
    if device.startswith("cuda") and not c.task_gpus:
        c = replace(c, task_gpus=1.0)
    if threads:
        c = replace(c, task_cpus=threads)
    render = ClusterRender(scene, settings, c)
    if resume is not None:
        render.restore(load_checkpoint(resume), source=str(resume))
    return render
