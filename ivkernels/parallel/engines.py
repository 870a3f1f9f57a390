"""Where the tasks of :func:`ivkernels.decompose_many` run: this process, or a Ray cluster.

Both engines take tasks with :meth:`submit` and hand back finished ones,
one at a time, with :meth:`next_done` as ``(key, result)`` where ``result``
is an :class:`ivkernels.IntrinsicVideo` or the exception the task raised.

* :class:`LocalEngine` runs each task in this process when it is asked for
  the next finished one, in submission order.
* :class:`RayEngine` runs each task as a Ray task holding one CPU, with the
  kernels on one thread to match, unless the call has too few tasks to keep
  every CPU busy to its end (:func:`task_cpus`).  Frames go into Ray's
  object store once (``ray.put``; a worker on the same node reads them
  without a copy, NumPy arrays being stored out of band) and results come
  back through it.  A task whose worker dies (killed, out of memory, node
  lost) is run again, up to ``max_retries`` times; an exception raised by
  the task itself is not retried (it would fail again).  Before the first
  task, each node runs :func:`ivkernels.parallel.tasks.warm_up` once (once
  per process and cluster); on a local cluster the call starts, this
  process warms the machine's kernel cache while the cluster starts.

Ray is an optional dependency (``pip install ivkernels[ray]``), imported
only here and only when a :class:`RayEngine` is made.
"""
from __future__ import annotations

import logging
import os
from collections import deque
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ivkernels.decompose import IntrinsicVideo
from ivkernels.parallel import tasks


def _own_copy(video: IntrinsicVideo) -> IntrinsicVideo:
    """``video`` with writable arrays of its own (a Ray result's arrays are read-only views
    into the object store, which they would keep pinned while referenced)."""
    def copy(x):
        return None if x is None else np.array(x, copy=True)

    return IntrinsicVideo(copy(video.albedo), copy(video.shading), copy(video.flow),
                          copy(video.occlusion), copy(video.boundary), dict(video.diagnostics))


#: ``ray.init`` arguments of the local cluster started when none is given: a new one
#: (``address="local"``; a plain ``ray.init()`` would join a cluster that ``ray start`` left
#: on this machine), every core of this machine, no dashboard, and the workers at the
#: priority of the process that starts them (Ray's default lowers them to nice 15, which on a
#: machine shared with other programs hands those programs the workers' cores).
LOCAL_CLUSTER = dict(address="local", include_dashboard=False, logging_level=logging.WARNING,
                     _system_config={"worker_niceness": 0})


#: ``(node id, kernels)`` pairs warmed by this process: a later call on the same cluster skips
#: them (the kernels are in the node's on-disk caches; node ids are unique per cluster).
_warmed: set = set()


def task_cpus(n_tasks: int, cpus: int, node_cpus: int) -> float:
    """The CPUs each task of a call holds (its Ray ``num_cpus``), so that no CPU idles
    while the call's last tasks finish; the kernels run on ``max(1, int(share))`` threads.

    Parameters
    ----------
    n_tasks : the call's tasks (videos and chunks).
    cpus : the cluster's CPUs; ``node_cpus``: those of its largest node.

    Returns
    -------
    * ``1`` with at least twice as many tasks as CPUs (each CPU takes the next
      task as it finishes one; the last round is a small part of the call)
      or exactly as many;
    * ``cpus / n_tasks`` (rounded down to Ray's 1e-4 resolution) with more
      tasks than CPUs but fewer than twice as many: all of them run at once
      and the operating system shares the CPUs among them, instead of a
      last round that leaves CPUs idle (three chunks on 2 CPUs: the time of
      1.5 chunks instead of 2; perf/RESULTS.md, "Chunks on Ray: where the
      time goes");
    * ``cpus // n_tasks`` (at most ``node_cpus``) with fewer tasks than CPUs,
      the kernels on as many threads.

    >>> task_cpus(4, 2, 2), task_cpus(3, 2, 2), task_cpus(1, 2, 2), task_cpus(1, 8, 4)
    (1, 0.6666, 2, 4)
    """
    if n_tasks >= 2 * cpus or n_tasks == cpus or n_tasks < 1:
        return 1
    if n_tasks > cpus:
        return int(cpus / n_tasks * 1e4) / 1e4
    return max(1, min(cpus // n_tasks, node_cpus))


class LocalEngine:
    """Runs the tasks in this process, one after another, with the caller's options."""

    name = "local"

    def __init__(self, options: dict):
        self.options = options
        self._queue: deque = deque()

    def capacity(self) -> int:
        """Tasks worth having submitted at once (one: each runs when asked for)."""
        return 1

    def expect(self, n_tasks: int) -> None:
        """Nothing to set: each task runs with the caller's options."""

    def in_flight(self) -> int:
        return len(self._queue)

    def submit(self, key, frames, flow, params=None) -> None:
        """Queue a task; ``params`` (an :class:`ivkernels.Params`) replaces the options' for it."""
        self._queue.append((key, frames, flow, params))

    def next_done(self):
        key, frames, flow, params = self._queue.popleft()
        options = self.options if params is None else dict(self.options, params=params)
        try:
            return key, tasks.solve(frames, flow, options)
        except Exception as err:            # reported per video by the caller
            return key, err

    def cancel(self) -> None:
        self._queue.clear()

    def close(self) -> None:
        self._queue.clear()


def import_ray():
    try:
        import ray
    except ImportError as err:
        raise ImportError("engine='ray' needs Ray: pip install 'ivkernels[ray]' "
                          "(or use engine='local')") from err
    return ray


class RayEngine:
    """Runs the tasks on a Ray cluster (see the module docstring).

    Parameters
    ----------
    options : keyword arguments of :func:`ivkernels.decompose` for every
        task; ``threads`` is set to 1 (one CPU per task), or to the CPUs a
        task holds after :meth:`expect`.
    address : a running cluster to join (``"auto"``, ``"ray://host:port"``
        or ``"host:port"``).  ``None``: the Ray connection this process
        already has, else the cluster named by the ``RAY_ADDRESS``
        environment variable, else a local cluster on this machine started
        for the call and shut down by :meth:`close`.
    max_retries : times a task whose worker died is run again.
    warm_up_flow : the flow argument of the tasks, for the per-node warm-up.
    """

    name = "ray"

    def __init__(self, options: dict, address: str | None = None, max_retries: int = 3,
                 warm_up_flow=None):
        ray = self.ray = import_ray()
        self.options = dict(options, threads=1)
        self._started = False
        if not ray.is_initialized():
            if address is None and not os.environ.get("RAY_ADDRESS"):
                self._start_local_cluster(warm_up_flow)
            else:
                ray.init(address=address, logging_level=logging.WARNING)
            self._started = True
        self._refs: dict = {}
        self.task_cpus = 1
        try:
            self._solve = ray.remote(num_cpus=1, max_retries=max_retries,
                                     retry_exceptions=False)(tasks.solve_in_worker)
            self._options_ref = ray.put(self.options)
            self.warmed = self._warm_up(warm_up_flow)
        except BaseException:
            self.close()
            raise

    def _kernels(self, flow) -> tuple:
        """What decides the kernels a call compiles: backend, device, temporal terms, flow."""
        o = self.options
        return (o.get("backend", "warp"), o.get("device", "cpu"), o.get("temporal", True),
                flow if isinstance(flow, str) or flow is None else "given")

    def _start_local_cluster(self, flow) -> None:
        """``ray.init`` a local cluster, warming this machine's kernel cache meanwhile.

        Starting the cluster takes about 2 s, most of it waiting for the raylet to
        register; the warm-up's tiny decomposition (:func:`tasks.warm_up_here`) runs in
        a thread of this process during that wait, so the node needs no warm-up task
        (perf/RESULTS.md, "Ray's fixed cost per call").  Warp on the CPU only: the
        Taichi runtime and a CUDA context are process-wide, and are not this
        process's to start.
        """
        ray = self.ray
        kernels = self._kernels(flow)
        if kernels[:2] != ("warp", "cpu"):
            ray.init(**LOCAL_CLUSTER)
            return
        with ThreadPoolExecutor(1, thread_name_prefix="ivkernels-warm-up") as pool:
            warming = pool.submit(tasks.warm_up_here, self.options, flow)
            ray.init(**LOCAL_CLUSTER)       # should it raise, leaving the pool waits for the warm-up
            try:
                warming.result()            # a failed warm-up raises here, as a failed task would
            except BaseException:
                ray.shutdown()
                raise
        _warmed.add((ray.get_runtime_context().get_node_id(), kernels))

    def _warm_up(self, flow) -> list[str]:
        """Run :func:`tasks.warm_up` once on each alive node with a CPU that this process has
        not warmed for these kernels yet (:data:`_warmed`); returns the node ids warmed now."""
        ray = self.ray
        from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

        kernels = self._kernels(flow)
        nodes = [node["NodeID"] for node in ray.nodes()
                 if node.get("Alive") and node.get("Resources", {}).get("CPU", 0) >= 1
                 and (node["NodeID"], kernels) not in _warmed]
        warm = ray.remote(num_cpus=1, max_retries=1)(tasks.warm_up)
        refs = [warm.options(scheduling_strategy=NodeAffinitySchedulingStrategy(node, soft=False))
                .remote(self._options_ref, flow) for node in nodes]
        done = ray.get(refs)
        _warmed.update((node, kernels) for node in done)
        return done

    def capacity(self) -> int:
        """Tasks kept submitted at once: twice the cluster's CPUs, so every CPU has its next
        task waiting while the object store holds the frames of a bounded number of tasks."""
        return max(2, 2 * self.cpus())

    def cpus(self) -> int:
        """The cluster's CPUs."""
        return max(1, int(self.ray.cluster_resources().get("CPU", 1)))

    def expect(self, n_tasks: int) -> None:
        """Size the tasks submitted from now on for a call of ``n_tasks`` tasks: each holds
        :func:`task_cpus` CPUs, with the kernels on as many threads (at least one)."""
        node_cpus = max((int(n.get("Resources", {}).get("CPU", 0)) for n in self.ray.nodes()
                         if n.get("Alive")), default=1)
        self.task_cpus = task_cpus(n_tasks, self.cpus(), max(1, node_cpus))
        threads = max(1, int(self.task_cpus))
        self._solve = self._solve.options(num_cpus=self.task_cpus)
        if threads != self.options["threads"]:
            self.options = dict(self.options, threads=threads)
            self._options_ref = self.ray.put(self.options)

    def in_flight(self) -> int:
        return len(self._refs)

    def submit(self, key, frames, flow, params=None) -> None:
        """Start a task; ``params`` (an :class:`ivkernels.Params`) replaces the options' for it
        (a chunk's longer windows; a small object, passed with the task)."""
        ray = self.ray
        frames_ref = ray.put(frames)
        flow_ref = ray.put(flow) if flow is not None and not isinstance(flow, str) else flow
        options = self._options_ref if params is None else dict(self.options, params=params)
        self._refs[self._solve.remote(frames_ref, flow_ref, options)] = key

    def next_done(self):
        ray = self.ray
        ready, _ = ray.wait(list(self._refs), num_returns=1)
        ref = ready[0]
        key = self._refs.pop(ref)
        try:
            return key, _own_copy(ray.get(ref))
        except ray.exceptions.RayTaskError as err:
            cause = err.cause if isinstance(getattr(err, "cause", None), BaseException) else err
            return key, cause
        except ray.exceptions.RayError as err:   # worker died more than max_retries times, ...
            return key, err

    def cancel(self) -> None:
        for ref in list(self._refs):
            self.ray.cancel(ref, force=True)
        self._refs.clear()

    def close(self) -> None:
        self.cancel()
        if self._started:
            self.ray.shutdown()
            self._started = False
