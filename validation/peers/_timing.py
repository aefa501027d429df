"""Shared timing and reporting for the peer scripts in validation/peers/ (see validation/peers/README.md).

Every script prints its results as lines
    ROW|peer|operation|precision|batch|median_ns_per_item|min_ns_per_item|note
which validation/peers/run.sh collects into one table; a peer that cannot be measured prints
    ROW|peer|operation|-|-|-|-|SKIPPED: <reason>
"""

import statistics
import sys
import time


def bench(call, items, *, warmup=3, samples=21, min_sample_s=0.02, max_total_s=20.0):
    """Times `call()` (which processes `items` items) with time.perf_counter.

    After `warmup` untimed calls, the number of calls per sample is calibrated so that one
    sample lasts at least `min_sample_s`; then `samples` samples are taken (fewer if
    `max_total_s` would be exceeded, but at least 5). Returns (median, min) in ns per item.
    """
    for _ in range(warmup):
        call()
    reps = 1
    while True:
        t0 = time.perf_counter()
        for _ in range(reps):
            call()
        dt = time.perf_counter() - t0
        if dt >= min_sample_s:
            break
        reps *= 2
    n_samples = max(5, min(samples, int(max_total_s / max(dt, 1e-9))))
    per_item = []
    for _ in range(n_samples):
        t0 = time.perf_counter()
        for _ in range(reps):
            call()
        dt = time.perf_counter() - t0
        per_item.append(dt * 1e9 / (reps * items))
    return statistics.median(per_item), min(per_item)


def row(peer, operation, precision, batch, median_ns, min_ns, note=""):
    print(f"ROW|{peer}|{operation}|{precision}|{batch}|{median_ns:.4g}|{min_ns:.4g}|{note}")
    sys.stdout.flush()


def skip(peer, operation, reason):
    reason = " ".join(str(reason).split())
    print(f"ROW|{peer}|{operation}|-|-|-|-|SKIPPED: {reason}")
    sys.stdout.flush()
