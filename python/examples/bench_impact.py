"""The cost per row of ``ricochet.impact``, on the problems of the Rust benchmark
``benches/impact.rs`` (each law on a reverse-sliding, a sticking and a forward-sliding
problem), to compare with its time per call of ``impact::solve``:

    cargo bench -p ricochet-benches --bench impact
    python python/examples/bench_impact.py [ROWS]
"""

from __future__ import annotations

import sys
import time

import numpy as np

import ricochet
from ricochet import _ricochet

PROBLEMS = {
    "reverse": ([0.33652, -0.50710, 0.81345], [-0.2684, 0.5343], 0.5, 0.2),
    "stick": ([1.0, 0.2, 2.0], [-1.0, 0.3], 0.6, 0.8),
    "forward": ([1.0, 0.2, 2.0], [-1.0, -5.0], 0.6, 0.2),
}


def best(f, repeat: int = 5) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 100_000
    print(f"{n} rows per call; ns per row, best of 5")
    print(f"{'law/problem':<26} {'impact()':>10} {'_solve_rows':>12}")
    for law in ricochet.LAWS:
        for name, (w, v, e, mu) in PROBLEMS.items():
            w_n = np.tile(w, (n, 1))
            v_n = np.tile(v, (n, 1))
            e_n = np.full(n, e)
            mu_n = np.full(n, mu)
            whole = best(lambda: ricochet.impact(w_n, v_n, e_n, mu_n, law=law))
            core = best(lambda: _ricochet._solve_rows(w_n, v_n, e_n, mu_n, law, False))
            print(f"{law + '/' + name:<26} {whole / n * 1e9:>10.1f} {core / n * 1e9:>12.1f}")


if __name__ == "__main__":
    main()
