"""Many videos and long videos on Ray: overheads, throughput, and a projection past one machine.

Four parts, each printing its table (``--parts``):

``overheads``
    On a local Ray cluster of 1 and of 2 CPUs: starting the cluster, the
    per-node warm-up, the scheduler's per-task cost (a no-op task, one at a
    time and many at once), the object store's cost per task (``ray.put``
    of one clip's frames, ``ray.get`` of one result), and the throughput of
    :func:`ivkernels.decompose_many` on ``--videos`` clips.
``many``
    The done criterion of the Ray issue: ``--videos`` clips of ``--frames``
    frames through ``decompose_many(engine="ray")`` (a local cluster started
    by the call, all cores) against ``decompose()`` one by one (all cores):
    time ratio and the largest albedo difference; then the same call on a
    local cluster that is already up and warm (no start, warm-up or
    shutdown in the call).
``chunks``
    A ``--long-frames`` video in ``--chunk-frames`` chunks on Ray against the
    sequential solve: time ratio, albedo LMSE, albedo drift first to last
    (``|exp(g_T - g_1) - 1|``, ``g_t`` the median over pixels and channels of
    ``log(estimate / truth)`` of frame t: how far the global albedo scale
    wanders), the change of the same surface points' albedo first to last
    (:func:`ivkernels.evaluation.metrics.tracked_albedo_change`: the median
    and the mean absolute change of the points followed along the true flow,
    and the fraction of the first frame followed to the last), and albedo
    flicker (:func:`ivkernels.metrics.albedo_flicker` along the true flow) on the frame pairs at the seams and elsewhere;
    each chunked call twice, its tasks sharing the CPUs
    (:func:`ivkernels.parallel.engines.task_cpus`) and on one CPU each (as
    before it), side by side, ``--repeats`` times (``--shares`` picks
    them); and with ``--chunk-windows params chunk`` each of those with the
    chunks solved in windows of ``Params.window`` frames (as before
    :func:`ivkernels.parallel.chunks.chunk_params`) and in the chunks'
    longer windows (now), side by side; the "windows" column lists each
    chunk's window ranges as its task reported them, and "CPU-s" the CPU
    seconds of the sequential solve (this process) and of all the chunks'
    tasks (their workers), which a load from other programs stretches less
    than the wall-clock ratio.
``phases``
    Where the seconds of one chunked call go: what a fresh worker process
    pays (imports, ``warp.init``, kernel loads), then, beside the
    sequential solve, a ``decompose_many`` call that starts its own local
    cluster, timed phase by phase (start, warm-up, puts, each chunk's solve
    in its worker, stitch, shutdown) with the CPU seconds of the chunks,
    before and after ``task_cpus``.

The projection (printed after ``overheads``) takes the measured per-task
figures and assumes the rest; see perf/RESULTS.md, "Many videos and long
videos on Ray".  Clips come from the project's renderer, training seeds
only (seed 0 is refused).

    python perf/scale.py                          # overheads, many, chunks: ~8 minutes on 2 cores
    python perf/scale.py --parts phases --repeats 2
    python perf/scale.py --parts chunks --kinds objects_camera --overlaps 2 4
    python perf/scale.py --parts chunks --shares task_cpus --chunk-windows params chunk
    python perf/scale.py --parts chunks --shares task_cpus --set lbfgs_iterations=160   # a Params field
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time

import numpy as np

import ivkernels as iv
from common import parse_grid
from ivkernels.evaluation import metrics, synthetic
from ivkernels.parallel import engines, many
from ivkernels.parallel.engines import LOCAL_CLUSTER, RayEngine

NODES = (1, 10, 100, 1000)
#: Assumed network bandwidth of one node (and of the driver), bytes/s: 10 Gbit/s Ethernet.
NODE_BANDWIDTH = 1.25e9


def _clips(n: int, frames: int, size: tuple, first_seed: int):
    kinds = synthetic.KINDS
    return [synthetic.render_sequence(kinds[i % len(kinds)], frames, size=size, seed=first_seed + i)
            for i in range(n)]


def _nbytes(video: iv.IntrinsicVideo) -> int:
    return sum(x.nbytes for x in (video.albedo, video.shading, video.flow, video.occlusion,
                                  video.boundary) if x is not None)


def _noop(x):
    return x.shape


def measure_overheads(args) -> dict:
    import ray

    clips = _clips(args.videos, args.frames, tuple(args.size), args.seed)
    frames = [c.frames for c in clips]
    t0, c0 = time.perf_counter(), time.process_time()
    serial = [iv.decompose(f, threads=1) for f in frames]
    serial_1 = (time.perf_counter() - t0) / len(clips)
    cpu_1 = (time.process_time() - c0) / len(clips)
    out = {"task_seconds": serial_1, "task_cpu": cpu_1, "bytes_in": frames[0].nbytes,
           "bytes_out": _nbytes(serial[0])}
    print(f"\none {args.frames}-frame {args.size[1]}x{args.size[0]} clip, decompose(threads=1) in this "
          f"process: {serial_1:.2f} s, {cpu_1:.2f} CPU-s; in {out['bytes_in'] / 1e6:.2f} MB (linear "
          f"float32 frames), out {out['bytes_out'] / 1e6:.2f} MB (float32 albedo, shading, flow, maps)")
    print("\n| CPUs | start s | warm-up s | no-op task, one at a time ms | no-op tasks/s, 200 at once "
          "| put frames ms | get result ms | videos/s | speed-up | task CPU-s |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    rows = {}
    for cpus in (1, 2):
        t0 = time.perf_counter()
        ray.init(num_cpus=cpus, **LOCAL_CLUSTER)
        start = time.perf_counter() - t0
        noop = ray.remote(num_cpus=1)(_noop)
        small = np.zeros(4)
        ray.get(noop.remote(small))
        t0 = time.perf_counter()
        for _ in range(50):
            ray.get(noop.remote(small))
        one = (time.perf_counter() - t0) / 50
        t0 = time.perf_counter()
        ray.get([noop.remote(small) for _ in range(200)])
        many = 200 / (time.perf_counter() - t0)
        t0 = time.perf_counter()
        refs = [ray.put(f) for f in frames]
        put = (time.perf_counter() - t0) / len(frames)
        ref = ray.put(serial[0])
        t0 = time.perf_counter()
        for _ in range(10):
            got = ray.get(ref)
            _ = [np.array(x, copy=True) for x in (got.albedo, got.shading, got.flow)]
        get = (time.perf_counter() - t0) / 10
        del refs, ref, got
        t0 = time.perf_counter()
        RayEngine({}, max_retries=0)
        warm = time.perf_counter() - t0
        t0 = time.perf_counter()
        results = iv.decompose_many(frames, engine="ray")
        rate = len(frames) / (time.perf_counter() - t0)
        diff = max(float(np.abs(a.albedo - b.albedo).max()) for a, b in zip(results, serial))
        ray.shutdown()
        task_cpu = float(np.mean([r.diagnostics["task"]["cpu_seconds"] for r in results]))
        rows[cpus] = dict(start=start, warm=warm, one=one, many=many, put=put, get=get, rate=rate,
                          diff=diff, task_cpu=task_cpu)
        print(f"| {cpus} | {start:.2f} | {warm:.2f} | {one * 1e3:.2f} | {many:.0f} | {put * 1e3:.2f} | "
              f"{get * 1e3:.2f} | {rate:.3f} | {rate / rows[1]['rate']:.2f} | {task_cpu:.2f} |")
    print(f"largest albedo difference from decompose(): {max(r['diff'] for r in rows.values()):.2e}")
    out.update(rows=rows)
    project(out)
    return out


def project(m: dict) -> None:
    """Throughput for 10-1000 nodes from the measured per-task figures (assumptions in RESULTS.md)."""
    r2 = m["rows"][2]
    # CPU seconds, not wall seconds: on a shared machine the wall time stretches with the
    # load, the CPU a task needs much less; a node of the projection runs nothing else
    task = r2["task_cpu"]                          # one task on a Ray worker, one thread
    per_task_cpu = task - m["task_cpu"]            # beyond the same solve in this process
    driver = r2["put"] + r2["get"]                 # driver seconds per task: put frames, get result
    traffic = m["bytes_in"] + m["bytes_out"]
    print(f"\nprojection: {task:.2f} CPU-s/task on a worker ({m['task_cpu']:.2f} in this process, "
          f"{per_task_cpu:+.2f}), driver {driver * 1e3:.1f} ms/task, object-store traffic "
          f"{traffic / 1e6:.2f} MB/task, scheduler {r2['many']:.0f} tasks/s (one driver), "
          f"{NODE_BANDWIDTH / 1e9:.2f} GB/s per link (assumed)")
    print("\n| nodes x cores | compute-bound videos/s | driver-bound videos/s | network-bound videos/s "
          "| scheduler-bound videos/s | projected videos/s | limited by |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for cores in (2, 32):
        for nodes in NODES:
            compute = nodes * cores / task
            bounds = {"compute": compute, "driver": 1 / driver, "network": NODE_BANDWIDTH / traffic,
                      "scheduler": r2["many"]}
            limit = min(bounds, key=bounds.get)
            print(f"| {nodes} x {cores} | {compute:.1f} | {bounds['driver']:.0f} | {bounds['network']:.0f} | "
                  f"{bounds['scheduler']:.0f} | {bounds[limit]:.1f} | {limit} |")


def measure_many(args) -> None:
    clips = _clips(args.videos, args.frames, tuple(args.size), args.seed)
    frames = [c.frames for c in clips]
    t0 = time.perf_counter()
    serial = [iv.decompose(f) for f in frames]
    t_serial = time.perf_counter() - t0
    t0 = time.perf_counter()
    results = iv.decompose_many(frames, engine="ray")
    t_ray = time.perf_counter() - t0
    diff = max(float(np.abs(a.albedo - b.albedo).max()) for a, b in zip(results, serial))
    print(f"\n{len(frames)} videos of {args.frames} frames {args.size[1]}x{args.size[0]} (seeds "
          f"{args.seed}..{args.seed + len(frames) - 1}): decompose() one by one {t_serial:.1f} s, "
          f"decompose_many(engine='ray') {t_ray:.1f} s (cluster start and shutdown included), "
          f"ratio {t_ray / t_serial:.2f}; largest albedo difference {diff:.2e}")
    # the same call joining a cluster that is already up and warm (a user who runs Ray already):
    # no start, warm-up or shutdown in the call
    import ray
    ray.init(**LOCAL_CLUSTER)
    try:
        iv.decompose_many([f[:3] for f in frames[:1]], engine="ray")     # workers up and warm, not timed
        t0 = time.perf_counter()
        joined = iv.decompose_many(frames, engine="ray")
        t_join = time.perf_counter() - t0
    finally:
        ray.shutdown()
    diff = max(float(np.abs(a.albedo - b.albedo).max()) for a, b in zip(joined, serial))
    print(f"the same on a running local cluster of this machine's CPUs: {t_join:.1f} s, ratio "
          f"{t_join / t_serial:.2f}; largest albedo difference {diff:.2e}")


def _drift(albedo, truth) -> float:
    g = [np.median(np.log(np.maximum(albedo[t], 1e-6)) - np.log(np.maximum(truth[t], 1e-6)))
         for t in (0, len(albedo) - 1)]
    return abs(float(np.exp(g[1] - g[0])) - 1)


def _pair_flicker(albedo, seq, pairs) -> float:
    # the albedo of the whole video scaled once (as albedo_flicker does), then pair by pair
    a = albedo / np.percentile(albedo, 99)
    return float(np.mean([metrics.albedo_flicker(a[t:t + 2], seq.flow[t:t + 1], seq.visibility[t:t + 1])
                          for t in pairs]))


def measure_chunks(args) -> None:
    import ray

    print("\n| kind | seed | overlap | repeat | tasks hold | chunk windows | chunks | windows | sequential s | "
          "chunked s | ratio | CPU-s seq / chunks | LMSE seq | LMSE chunked | LMSE ratio | drift seq | drift chunked | "
          "tracked change seq / chunked (median, mean abs) | tracked | "
          "flicker at seams seq / chunked | flicker elsewhere seq / chunked |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- "
          "| --- | --- |")
    # each task on one CPU (as before engines.task_cpus), against the CPUs shared by the call's tasks
    shares = {"1 CPU (before)": lambda n_tasks, cpus, node_cpus: 1, "task_cpus": engines.task_cpus}
    shares = {name: fn for name, fn in shares.items() if name.split()[0] in args.shares}
    # chunks in windows of Params.window (as before chunks.chunk_params), or in the chunks' own
    windows = {"params": lambda params, n_frames: params, "chunk": many.chunk_params}
    runs = [(share, win) for share in shares for win in args.chunk_windows]
    params = iv.Params(**parse_grid(args.set)[0])
    for kind in args.kinds:
        seq = synthetic.render_sequence(kind, args.long_frames, size=tuple(args.size), seed=args.seed)
        frames = seq.frames
        for repeat in range(args.repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            ref = iv.decompose(frames, params=params)
            t_seq, c_seq = time.perf_counter() - t0, time.process_time() - c0
            ray.init(**LOCAL_CLUSTER)
            iv.decompose_many([frames[:3]], engine="ray")        # cluster up and workers warm, not timed
            for overlap in args.overlaps:
                for name, win in (runs if repeat % 2 == 0 else runs[::-1]):
                    saved = engines.task_cpus, many.chunk_params
                    engines.task_cpus, many.chunk_params = shares[name], windows[win]
                    try:
                        t0 = time.perf_counter()
                        out = iv.decompose_many([frames], engine="ray", chunk_frames=args.chunk_frames,
                                                chunk_overlap=overlap, params=params)[0]
                        t_ch = time.perf_counter() - t0
                    finally:
                        engines.task_cpus, many.chunk_params = saved
                    solved = " ".join("+".join(f"{a}-{b}" for a, b in d["windows"])
                                      for d in out.diagnostics["chunk_diagnostics"])
                    # CPU seconds of the sequential solve (this process, all its threads) and of
                    # the chunks' tasks (each in its worker): the work, whatever else loads the machine
                    c_ch = sum(d["task"]["cpu_seconds"] for d in out.diagnostics["chunk_diagnostics"])
                    ranges = out.diagnostics["chunks"]
                    seam_pairs = sorted({t for (start, _), (_, prev_stop) in zip(ranges[1:], ranges[:-1])
                                         for t in range(max(start - 1, 0),
                                                        min(prev_stop, args.long_frames - 1))})
                    other = [t for t in range(args.long_frames - 1) if t not in seam_pairs]
                    l_seq, l_ch = metrics.lmse(ref.albedo, seq.albedo), metrics.lmse(out.albedo, seq.albedo)
                    # the same surface points first to last, along the true flow (metrics.tracked_albedo_change)
                    k_seq = metrics.tracked_albedo_change(ref.albedo, seq.flow, seq.visibility)
                    k_ch = metrics.tracked_albedo_change(out.albedo, seq.flow, seq.visibility)
                    print(f"| {kind} | {args.seed} | {overlap} | {repeat + 1} | {name} | {win} | "
                          f"{' '.join(f'{a}-{b}' for a, b in ranges)} | {solved} | {t_seq:.1f} | {t_ch:.1f} | "
                          f"{t_ch / t_seq:.2f} | {c_seq:.1f} / {c_ch:.1f} | {l_seq:.4f} | {l_ch:.4f} | {l_ch / l_seq:.3f} | "
                          f"{_drift(ref.albedo, seq.albedo):.4f} | {_drift(out.albedo, seq.albedo):.4f} | "
                          f"{k_seq['median']:+.4f}, {k_seq['mean_abs']:.4f} / {k_ch['median']:+.4f}, "
                          f"{k_ch['mean_abs']:.4f} | {k_ch['tracked']:.2f} | "
                          f"{_pair_flicker(ref.albedo, seq, seam_pairs):.4f} / "
                          f"{_pair_flicker(out.albedo, seq, seam_pairs):.4f} | "
                          f"{_pair_flicker(ref.albedo, seq, other):.4f} / "
                          f"{_pair_flicker(out.albedo, seq, other):.4f} |", flush=True)
            ray.shutdown()
        print(f"load average at the end {os.getloadavg()[0]:.2f}")


#: What a fresh worker process pays before its first task's solve, measured in a fresh
#: interpreter: the imports, Warp's initialisation, and the first tiny solve (Warp loads
#: every kernel module from its on-disk cache) against the second.
_FRESH_PROCESS = """
import time
t0 = time.perf_counter()
import ivkernels.parallel.tasks as tasks
t1 = time.perf_counter()
import warp
warp.config.quiet = True
warp.init()
t2 = time.perf_counter()
tasks.prepare_process("warp", 1)
import numpy as np
frames = np.random.default_rng(1).uniform(0.2, 0.8, (3, 48, 64, 3)).astype(np.float32)
t3 = time.perf_counter()
tasks.solve(frames, None, {"threads": 1})
t4 = time.perf_counter()
tasks.solve(frames, None, {"threads": 1})
t5 = time.perf_counter()
print(t1 - t0, t2 - t1, t4 - t3, t5 - t4)
"""


def measure_phases(args) -> None:
    """Where a chunked call's seconds go: a timeline of one ``decompose_many`` call that starts
    its own local cluster, before and after this round's changes, beside the sequential solve
    of the same video (same run)."""
    out = subprocess.run([sys.executable, "-c", _FRESH_PROCESS], capture_output=True, text=True,
                         check=True, env=dict(os.environ, PYTHONWARNINGS="ignore"))
    imp, warp_init, first, second = map(float, out.stdout.split()[-4:])
    print(f"\na fresh process (as a Ray worker): import ivkernels {imp:.2f} s, warp.init {warp_init:.2f} s, "
          f"first 3-frame 48x64 solve {first:.2f} s, second {second:.2f} s (kernel loads "
          f"{first - second:.2f} s)")

    seq = synthetic.render_sequence(args.kinds[0], args.long_frames, size=tuple(args.size), seed=args.seed)
    frames = seq.frames
    for repeat in range(args.repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        ref = iv.decompose(frames)
        t_seq, c_seq = time.perf_counter() - t0, time.process_time() - c0
        print(f"\nrepeat {repeat + 1}, load average {os.getloadavg()[0]:.2f}: sequential {t_seq:.1f} s "
              f"({c_seq:.1f} CPU-s of this process); LMSE {metrics.lmse(ref.albedo, seq.albedo):.4f}, "
              f"drift {_drift(ref.albedo, seq.albedo):.4f}")
        for before in ((True, False) if repeat % 2 == 0 else (False, True)):
            t_ch, out, events, pids, t0 = _timeline_call(frames, args.chunk_frames, before)
            print(f"\n{'before' if before else 'after'} (load average {os.getloadavg()[0]:.2f}): chunked "
                  f"{t_ch:.1f} s, ratio {t_ch / t_seq:.2f}; LMSE {metrics.lmse(out.albedo, seq.albedo):.4f}, "
                  f"drift {_drift(out.albedo, seq.albedo):.4f}; chunks {out.diagnostics.get('chunks')}")
            _print_timeline(t_ch, out, events, pids, t0)


def _timeline_call(frames, chunk_frames, before: bool):
    """One ``decompose_many`` call that starts its own local cluster, its phases timed;
    ``before``: each task on one CPU (as before :func:`engines.task_cpus`)."""
    import psutil
    import ray

    from ivkernels.parallel import many

    events = []                                   # (label, start, stop), time.time()
    pids = {}

    def timed(label, fn):
        def wrapper(*a, **k):
            s = time.time()
            try:
                return fn(*a, **k)
            finally:
                events.append((label, s, time.time()))
        return wrapper

    def next_done(self, _fn=engines.RayEngine.next_done):
        key, result = timed("next_done (wait, get)", _fn)(self)
        if not isinstance(result, BaseException):
            pids[key] = psutil.Process(result.diagnostics["task"]["pid"]).create_time()
        return key, result

    patches = [(ray, "init", timed("ray.init", ray.init)),
               (ray, "shutdown", timed("ray.shutdown", ray.shutdown)),
               (engines.RayEngine, "_warm_up", timed("warm-up tasks", engines.RayEngine._warm_up)),
               (engines.RayEngine, "submit", timed("submit (put frames)", engines.RayEngine.submit)),
               (engines.RayEngine, "next_done", next_done), (many, "stitch", timed("stitch", many.stitch))]
    if before:
        patches += [(engines, "task_cpus", lambda n_tasks, cpus, node_cpus: 1)]
    saved = [(obj, name, getattr(obj, name)) for obj, name, _ in patches]
    for obj, name, value in patches:
        setattr(obj, name, value)
    engines._warmed.clear()
    try:
        t0 = time.time()
        out = iv.decompose_many([frames], engine="ray", chunk_frames=chunk_frames)[0]
        t_ch = time.time() - t0
    finally:
        for obj, name, value in saved:
            setattr(obj, name, value)
    return t_ch, out, [(label, s - t0, e - t0) for label, s, e in events], \
        {key: created - t0 for key, created in pids.items()}, t0


def _print_timeline(t_ch, out, events, pids, t0) -> None:
    """The phases of one call (seconds from its start), and how busy the CPUs were while
    the chunks were solved (their CPU seconds, flow-ahead threads included)."""
    rows = list(events)
    chunk_tasks = [d["task"] for d in out.diagnostics.get("chunk_diagnostics", [out.diagnostics])]
    for c, task in enumerate(chunk_tasks):
        rows.append((f"chunk {c} solve (pid {task['pid']}, holds {task['cpus']} CPU, "
                     f"{task['threads']} thread, {task['cpu_seconds']:.1f} CPU-s)",
                     task["started"] - t0, task["finished"] - t0))
    for key, created in sorted(pids.items()):
        rows.append((f"worker of chunk {key[1]} started", created, created))
    merged: dict = {}
    for label, s, e in rows:                      # repeated phases: first start, last end, summed
        m = merged.setdefault(label, [s, e, 0.0])
        m[0], m[1], m[2] = min(m[0], s), max(m[1], e), m[2] + e - s
    print("\n| phase | from s | to s | seconds |\n| --- | --- | --- | --- |")
    for label, (s, e, total) in sorted(merged.items(), key=lambda kv: kv[1][0]):
        print(f"| {label} | {s:.2f} | {e:.2f} | {total:.2f} |")
    first = min(t["started"] for t in chunk_tasks) - t0
    last = max(t["finished"] for t in chunk_tasks) - t0
    cpu = sum(t["cpu_seconds"] for t in chunk_tasks)
    cpus = os.cpu_count()
    print(f"\nchunks solved from {first:.2f} to {last:.2f} s: {cpu:.1f} CPU-s of {cpus} CPUs x "
          f"{last - first:.1f} s ({cpu / (cpus * (last - first)):.0%} busy with them); before the first "
          f"solve {first:.2f} s, after the last {t_ch - last:.2f} s")


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--parts", nargs="+", default=["overheads", "many", "chunks"],
                   choices=["overheads", "many", "chunks", "phases"])
    p.add_argument("--repeats", type=int, default=1, help="repeats of 'chunks' and 'phases'")
    p.add_argument("--videos", type=int, default=4, help="clips in 'overheads' and 'many'")
    p.add_argument("--frames", type=int, default=8, help="frames per clip")
    p.add_argument("--size", type=int, nargs=2, default=(120, 160), metavar=("H", "W"))
    p.add_argument("--seed", type=int, default=1, help="first training seed (not 0)")
    p.add_argument("--long-frames", type=int, default=36)
    p.add_argument("--chunk-frames", type=int, default=12)
    p.add_argument("--overlaps", type=int, nargs="+", default=[2], help="chunk overlaps to measure")
    p.add_argument("--kinds", nargs="+", default=["static_moving_light"], choices=synthetic.KINDS)
    p.add_argument("--shares", nargs="+", default=["1", "task_cpus"], choices=["1", "task_cpus"],
                   help="'chunks': each task on 1 CPU (as before task_cpus), the CPUs shared (task_cpus)")
    p.add_argument("--chunk-windows", nargs="+", default=["chunk"], choices=["params", "chunk"],
                   help="'chunks': windows of Params.window inside a chunk (as before chunk_params), "
                        "the chunks' own (chunk_params)")
    p.add_argument("--set", nargs="*", default=[], metavar="NAME=VALUE",
                   help="'chunks': Params fields of both the sequential and the chunked solve")
    args = p.parse_args(argv)
    if args.seed == 0:
        p.error("seed 0 is the evaluation seed; measure on training seeds (1 and up)")
    print(f"nproc {os.cpu_count()}, load average {os.getloadavg()[0]:.2f}, ray "
          f"{__import__('ray').__version__}")
    if "overheads" in args.parts:
        measure_overheads(args)
    if "many" in args.parts:
        measure_many(args)
    if "chunks" in args.parts:
        measure_chunks(args)
    if "phases" in args.parts:
        measure_phases(args)


if __name__ == "__main__":
    main()
