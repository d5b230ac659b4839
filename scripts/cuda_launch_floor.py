#!/usr/bin/env python3
"""What an empty kernel costs through CUDA, timed as the peers' README times cuda_voxelizer's
`voxelize_triangle` (CUDA events around one launch, median of 40 after 20 warm-up launches).

The counterpart of `cargo xtask bench voxelize --modes empty,zeroed` (xtask/src/floor.rs), which
times the same empty kernel through wgpu the way fieldkit's rows are timed. Together they say how
much of each side's figure at small grids is the launch and the timing itself, not the work.
Runs on the GPU machine (CuPy is installed there); prints one JSON line per case.

  python3 scripts/cuda_launch_floor.py [--threads 69451] [--bytes 262144]

--threads  threads launched, in blocks of 64 (cuda_voxelizer launches one per triangle)
--bytes    also time a cudaMemset of this many bytes before the launch, inside the events
           (the bitset's clear, which cuda_voxelizer's figure leaves out and fieldkit's includes)
"""
import argparse, json

import numpy as np

EMPTY = r"""
extern "C" __global__ void empty(unsigned* words) {
    unsigned i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i == 0xffffffffu) words[0] = 1u;
}
"""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--threads", type=int, default=69451)
    ap.add_argument("--bytes", type=int, nargs="*", default=[262144, 2097152])
    ap.add_argument("--reps", type=int, default=40)
    ap.add_argument("--warmup", type=int, default=20)
    a = ap.parse_args()

    import cupy as cp

    kernel = cp.RawKernel(EMPTY, "empty")
    blocks = (a.threads + 63) // 64

    def measure(name, launch, extra):
        for _ in range(a.warmup):
            launch()
        cp.cuda.Device().synchronize()
        start, stop = cp.cuda.Event(), cp.cuda.Event()
        times = []
        for _ in range(a.reps):
            start.record()
            launch()
            stop.record()
            stop.synchronize()
            times.append(cp.cuda.get_elapsed_time(start, stop))
        t = np.array(times)
        print(json.dumps({"case": name, "threads": a.threads, **extra,
                          "ms_median": float(np.median(t)), "ms_min": float(t.min()),
                          "ms_max": float(t.max()), "reps": a.reps}), flush=True)

    words = cp.zeros(max(a.bytes + [4]) // 4, dtype=cp.uint32)
    measure("empty", lambda: kernel((blocks,), (64,), (words,)), {})
    for b in a.bytes:
        w = words[: max(b // 4, 1)]

        def launch(w=w, b=b):
            cp.cuda.runtime.memsetAsync(w.data.ptr, 0, b, cp.cuda.get_current_stream().ptr)
            kernel((blocks,), (64,), (w,))

        measure("memset+empty", launch, {"bytes": b})


if __name__ == "__main__":
    main()
