"""Speed and memory of decompose(), split by stage.

Every configuration runs in a fresh subprocess, so its peak resident memory
(``ru_maxrss``) and its kernel-compile time are its own; compile time is
reported apart (a warm-up decomposition of two tiny frames in the same
process) and excluded from the stage times.

Prints, in one run:
  1. 8 frames at 320x240 and 640x480: Warp on 1 and 2 threads and Taichi,
     seconds per stage (flow, maps, solve, ...), total, and the 2-thread speedup;
  2. 8, 16 and 32 frames at 320x240 (Warp, 2 threads, windows of 8 frames):
     seconds and peak memory, with the per-frame cost, to show linear growth;
  3. long videos streamed window by window (iter_decompose, as the command
     line does): 60 and 300 frames at 80x60, peak memory stays flat.

With ``--device cuda`` it prints instead, per size, Warp on the CPU (2
threads) beside Warp on the CUDA device, and their time ratio.

``--set NAME=VALUE ...`` changes Params fields in every configuration, so two
settings can be timed one after the other on the same machine.

    python perf/bench_solver.py [--quick] [--flow classic_nl_fast] [--device cuda]
    python perf/bench_solver.py --sizes 480 640 --set coarse_basis_levels=1
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time


def run_one(args) -> dict:
    """One configuration, in this process (called through --one)."""
    import numpy as np

    import ivkernels as iv
    from common import parse_grid
    from ivkernels.evaluation import synthetic
    from ivkernels.kernels.launch import set_threads

    set_threads(args.threads)
    params = iv.Params(**parse_grid(args.set)[0])
    if args.stream:
        return run_stream(args)
    tiny = synthetic.render_sequence("objects_camera", n_frames=2, size=(32, 40), seed=1)
    t0 = time.perf_counter()
    iv.decompose(tiny.frames, flow=args.flow, backend=args.backend, device=args.device)  # compile + load kernels
    compile_s = time.perf_counter() - t0
    seq = synthetic.render_sequence("objects_camera", n_frames=args.frames,
                                    size=(args.height, args.width), seed=1)
    rss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0 = time.perf_counter()
    video = iv.decompose(seq.frames, flow=args.flow, backend=args.backend, device=args.device,
                         flow_passes=args.flow_passes, params=params)
    total = time.perf_counter() - t0
    assert np.isfinite(video.albedo).all()
    peak_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {"total": total, "compile": compile_s, "stages": video.diagnostics["seconds"],
            "peak_mib": peak_kib / 1024, "rss_before_mib": rss_before / 1024}


def run_stream(args) -> dict:
    """A long video through iter_decompose, keeping nothing but a running checksum."""
    import numpy as np

    import ivkernels as iv
    from ivkernels.evaluation import synthetic

    # A long sequence made of renders of shorter ones (the renderer keeps whole
    # sequences in memory; the solver must not).
    chunk = 20
    parts = [synthetic.render_sequence("objects_camera", n_frames=chunk, size=(args.height, args.width),
                                       seed=s).frames for s in range((args.frames + chunk - 1) // chunk)]
    frames = np.concatenate(parts)[: args.frames]
    rss_frames = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0 = time.perf_counter()
    total, windows = 0.0, 0
    for res in iv.iter_decompose(frames, flow="dis"):
        total += float(res.albedo[res.n_carried:].sum())
        windows += 1
    seconds = time.perf_counter() - t0
    assert np.isfinite(total)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {"total": seconds, "windows": windows, "peak_mib": peak / 1024,
            "input_mib": frames.nbytes / 2**20, "rss_after_input_mib": rss_frames / 1024}


def spawn(backend: str, threads: int, frames: int, height: int, width: int, flow: str,
          stream: bool = False, flow_passes: int = 2, device: str = "cpu", settings=()) -> dict:
    cmd = [sys.executable, __file__, "--one", "--backend", backend, "--device", device, "--threads", str(threads),
           "--frames", str(frames), "--height", str(height), "--width", str(width), "--flow", flow,
           "--flow-passes", str(flow_passes)]
    if stream:
        cmd.append("--stream")
    if settings:
        cmd += ["--set", *settings]
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def compare_devices(args, sizes) -> int:
    """Warp on the CPU (2 threads) and on ``args.device``, 8 frames per size, side by side."""
    print(f"decompose(), 8 frames, flow={args.flow}; seconds per stage (compile excluded)")
    print(f"{'size':>9} {'device':>8} {'flow':>6} {'guide':>6} {'solve':>7} {'total':>7} {'compile':>8}")
    for h, w in sizes:
        totals = {}
        for device in ("cpu", args.device):
            r = spawn("warp", 2, 8, h, w, args.flow, flow_passes=args.flow_passes, device=device,
                      settings=args.set)
            totals[device] = r["total"]
            s = r["stages"]
            print(f"{w}x{h:<5} {device:>8} {s.get('flow', 0):6.2f} {s.get('guide', 0):6.2f} "
                  f"{s.get('solve', 0):7.2f} {r['total']:7.2f} {r['compile']:8.2f}")
        print(f"{w}x{h}: CPU / {args.device} time ratio {totals['cpu'] / totals[args.device]:.1f}")
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--one", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--backend", default="warp")
    parser.add_argument("--device", default="cpu",
                        help="'cuda': compare Warp on the CPU with Warp on the CUDA device, per size")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--height", type=int, default=240)
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--flow", default="classic_nl_fast",
                        help="flow method for every configuration")
    parser.add_argument("--flow-passes", type=int, default=2,
                        help="passes of flow and intrinsic video together (decompose's flow_passes)")
    parser.add_argument("--quick", action="store_true", help="small sizes (a smoke run)")
    parser.add_argument("--sizes", type=int, nargs="+", default=None, metavar="H W",
                        help="sizes (H W pairs) of section 1; default 240 320 480 640")
    parser.add_argument("--scaling-size", type=int, nargs=2, default=None, metavar=("H", "W"),
                        help="size of section 2; default the first of --sizes")
    parser.add_argument("--stream", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--set", nargs="*", default=[], metavar="NAME=VALUE",
                        help="Params fields for every configuration but the streamed ones")
    args = parser.parse_args(argv)
    if args.one:
        print(json.dumps(run_one(args)))
        return 0

    if args.sizes:
        if len(args.sizes) % 2:
            parser.error("--sizes takes H W pairs")
        sizes = list(zip(args.sizes[::2], args.sizes[1::2]))
    else:
        sizes = [(120, 160)] if args.quick else [(240, 320), (480, 640)]
    if args.device != "cpu":
        return compare_devices(args, sizes)
    configs = [("warp", 1), ("warp", 2), ("taichi", 1), ("taichi", 2)]
    print(f"decompose(), 8 frames, flow={args.flow}; seconds per stage (compile excluded)")
    header = f"{'size':>9} {'backend':>8} {'thr':>3} {'flow':>6} {'maps':>6} {'solve':>7} " \
             f"{'median':>7} {'total':>7} {'compile':>8} {'peak MiB':>9}"
    print(header)
    for h, w in sizes:
        results = {}
        for backend, threads in configs:
            r = spawn(backend, threads, 8, h, w, args.flow, flow_passes=args.flow_passes, settings=args.set)
            results[(backend, threads)] = r
            s = r["stages"]
            print(f"{w}x{h:<5} {backend:>8} {threads:>3} {s.get('flow', 0):6.2f} {s.get('maps', 0):6.2f} "
                  f"{s.get('solve', 0):7.2f} {s.get('median', 0):7.2f} {r['total']:7.2f} "
                  f"{r['compile']:8.2f} {r['peak_mib']:9.0f}")
        speedup = results[("warp", 1)]["total"] / results[("warp", 2)]["total"]
        tspeed = results[("taichi", 1)]["total"] / results[("taichi", 2)]["total"]
        ratio = results[("taichi", 2)]["total"] / results[("warp", 2)]["total"]
        print(f"{w}x{h}: 2 threads vs 1: Warp {speedup:.2f}x, Taichi {tspeed:.2f}x; "
              f"Taichi / Warp time ratio (2 threads) {ratio:.2f}")

    h, w = args.scaling_size or sizes[0]
    counts = [4, 8, 12] if args.quick else [8, 16, 32]
    print(f"\nscaling in frames at {w}x{h} (Warp, 2 threads, windows of 8 frames)")
    print(f"{'frames':>6} {'total s':>8} {'s/frame':>8} {'peak MiB':>9}")
    base = None
    for n in counts:
        r = spawn("warp", 2, n, h, w, args.flow, flow_passes=args.flow_passes, settings=args.set)
        per = r["total"] / n
        base = base or per
        print(f"{n:6d} {r['total']:8.2f} {per:8.3f} {r['peak_mib']:9.0f}   (s/frame vs first: {per / base:.2f})")

    print("\nlong videos streamed with iter_decompose at 80x60 (Warp, 2 threads, DIS flow)")
    print(f"{'frames':>6} {'windows':>7} {'total s':>8} {'s/frame':>8} {'input MiB':>9} "
          f"{'RSS after input':>15} {'peak MiB':>9}")
    for n in ([30, 60] if args.quick else [60, 300]):
        r = spawn("warp", 2, n, 60, 80, "dis", stream=True)
        print(f"{n:6d} {r['windows']:7d} {r['total']:8.1f} {r['total'] / n:8.3f} {r['input_mib']:9.1f} "
              f"{r['rss_after_input_mib']:15.0f} {r['peak_mib']:9.0f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
