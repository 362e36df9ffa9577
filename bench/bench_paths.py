"""Path-following benchmark (issue 12): the centre-clamped arch family through the public
API, MGDC against displacement control against the converged beam values, and timings.

Run: ``.venv/bin/python bench/bench_paths.py`` (``make bench`` calls it). Prints one line per
case: steps, first peak and minimum in EI h / l^3, their deviation from the beam values
(711/-338, 732/-363, 710/-356 for h/t = 6, 10, 20) and the warm wall time.
"""

from __future__ import annotations

import os
import sys

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from bench.timing import median_time  # noqa: E402

BEAM = {6: (711.0, -338.0), 10: (732.0, -363.0), 20: (710.0, -356.0)}


def warm_time(fn, runs=3):
    med, _, out = median_time(fn, runs, warm=True)
    return med, out


def main():
    from bench.cases import clamped_arch_push
    from validation.arch import arch, first_peak_index

    med, path = warm_time(clamped_arch_push, runs=7)
    print(f"arch benchmark (reference model, 101 nodes, h/t = 10, MGDC to 2.2 h): "
          f"median {med * 1e3:.1f} ms, {len(path)} steps (target <= 20 ms)")
    n_list = [int(v) for v in os.environ.get("BENCH_PATH_NODES", "101,401").split(",")]
    for setup in ("fix", "clamp"):
        for ht in (6, 10, 20):
            for n in n_list:
                row = []
                for method in ("mgdc", "displacement"):
                    def run():
                        st, mid, h, EI = arch(ht, n, setup)
                        return st.push(mid, (0.0, -1.0), 2.2 * h, method=method), h, EI
                    med, (p, h, EI) = warm_time(run, runs=1)
                    f = p.force / (EI * h / 0.1**3)
                    pk, mn = f[first_peak_index(f)], f.min()
                    row.append(f"{method:12s} {p.status:3s} {len(p):4d} steps peak {pk:6.1f} "
                               f"({pk / BEAM[ht][0] - 1:+.1%}) min {mn:6.1f} "
                               f"({mn / BEAM[ht][1] - 1:+.1%}) {med * 1e3:6.0f} ms")
                print(f"{setup:5s} h/t={ht:2d} n={n:3d}: " + " | ".join(row))
                sys.stdout.flush()


if __name__ == "__main__":
    main()
