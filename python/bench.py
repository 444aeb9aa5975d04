"""Points classified and rays cast per second from Python, for a scene file:
the same points and rays as the Rust example `batch_rate`
(crates/render/examples/batch_rate.rs), so the two rates compare the
binding's overhead. See docs/python.md.

    python python/bench.py SCENE [N] [RUNS]
"""
import sys
import time

import numpy as np

import komplex

A = np.array([0.8191725133961644, 0.6710436067037892, 0.5497004779019705])
B = np.array([0.7548776662466927, 0.5698402909980533, 0.4382651422619815])


def frac(x):
    return x - np.floor(x)


def best_of(runs, f):
    best = float("inf")
    for _ in range(runs):
        t = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t)
    return best, out


def main(scene_path, n=1_000_000, runs=5):
    scene = komplex.load(scene_path)
    boxes = [b["box"] for b in scene.blocks if b["box"] is not None]
    lo = np.min([b[0] for b in boxes], axis=0)
    hi = np.max([b[1] for b in boxes], axis=0)
    i = np.arange(n, dtype=np.float64)[:, None]
    points = lo + (hi - lo) * frac(0.5 + i * A)
    directions = frac(0.3 + i * B) - 0.5
    classify, owners = best_of(runs, lambda: scene.classify(points))
    cast, hits = best_of(runs, lambda: scene.cast(points, directions))
    print(f"classify: {n / classify / 1e6:.2f} M points/s ({np.count_nonzero(owners)} of {n} inside)")
    print(f"cast:     {n / cast / 1e6:.2f} M rays/s ({np.count_nonzero(hits.block)} of {n} hit)")


if __name__ == "__main__":
    main(sys.argv[1], *(int(a) for a in sys.argv[2:]))
