"""CUB/Thrust reference for the GPU sort bench (run on the NVIDIA machine, in the same run as
`benches/sort.rs`): median GPU time of cupy.sort (keys) and cupy.argsort + gather (key-value) on
uniform random 30-bit keys (like the xorshift keys of benches/sort.rs: radix sorts do not depend
on the values' order), timed with CUDA events after warm-up.

    python3 benches/cub_sort.py 1000000 16000000
"""
import sys

import cupy as cp
import numpy as np


def median_ms(fn, runs=21):
    start, stop = cp.cuda.Event(), cp.cuda.Event()
    for _ in range(3):
        fn()
    times = []
    for _ in range(runs):
        start.record()
        fn()
        stop.record()
        stop.synchronize()
        times.append(cp.cuda.get_elapsed_time(start, stop))
    return float(np.median(times))


for n in [int(a) for a in sys.argv[1:]] or [1_000_000, 16_000_000]:
    rng = np.random.default_rng(1)
    k = cp.asarray(rng.integers(0, 1 << 30, size=n, dtype=np.uint32))
    v = cp.arange(n, dtype=cp.uint32)
    ks = median_ms(lambda: cp.sort(k))
    kv = median_ms(lambda: v[cp.argsort(k)])
    print(f"cupy {cp.__version__} n={n}: sort (keys) {ks:.3f} ms, argsort+gather (key-value) {kv:.3f} ms")
