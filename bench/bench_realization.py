"""Benchmark: `empact.identification.realize_steps` vs `control.eigensys_realization`.

Problem size taken for the paper's Fig. 2 identification: 2 inputs, 2 outputs, order 16
(eight lightly damped modes between 2 and 80 Hz), 2000 step-response samples at 1 kHz, block
Hankel matrix with 100 block rows and 1800 block columns (all the data), plus a 100 x 100
block case. Both functions get the same Markov parameters (the differenced step responses)
and the same Hankel size; each is timed as the best of several repeats in this process.
`realize_steps` also converts to continuous time (logm) and simulates its model's step
responses for the fit; `eigensys_realization` returns the discrete model only.

Run: ``PYTHONPATH=src .venv/bin/python bench/bench_realization.py``
"""
from __future__ import annotations

import time

import control
import numpy as np
from scipy.optimize import linear_sum_assignment

from empact.identification import realize_steps

FS, N_T, ORDER, ROWS, COLS, REPEATS = 1000.0, 2000, 16, 100, 1800, 7


def truth(seed: int = 0) -> control.StateSpace:
    """Continuous 2x2 modal system of order `ORDER` [s]."""
    rng = np.random.default_rng(seed)
    n_modes = ORDER // 2
    w = 2 * np.pi * np.geomspace(2.0, 80.0, n_modes) * (1 + 0.05 * rng.uniform(-1, 1, n_modes))
    zeta = rng.uniform(0.02, 0.08, n_modes)
    blocks = [np.array([[0.0, 1.0], [-wk ** 2, -2 * zk * wk]]) for wk, zk in zip(w, zeta)]
    A = np.block([[blocks[i] if i == j else np.zeros((2, 2)) for j in range(n_modes)]
                  for i in range(n_modes)])
    B = np.zeros((ORDER, 2))
    B[1::2] = rng.normal(size=(n_modes, 2)) * w[:, None]
    return control.ss(A, B, rng.normal(size=(2, ORDER)), np.zeros((2, 2)))


def best_time(fn, repeats: int = REPEATS) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def compare(label: str, t: np.ndarray, steps: np.ndarray, sys_true, cols: int = COLS) -> str:
    markov = np.diff(steps, axis=0, prepend=np.zeros((1, 2, 2))).transpose(1, 2, 0)  # (p, m, l)
    t_ours, res = best_time(lambda: realize_steps(t, steps, ORDER, n_block_rows=ROWS,
                                                  n_block_cols=cols))
    t_era, (sys_era, _) = best_time(lambda: control.eigensys_realization(
        markov, ORDER, m=ROWS, n=cols, dt=True))
    z = np.exp(2j * np.pi * np.linspace(0.5, FS / 2 * 0.98, 800) / FS)
    G_ours, G_era = res.sys_discrete(z), sys_era(z)
    G_true = control.c2d(sys_true, 1 / FS)(z)
    rel = lambda a, b: float(np.max(np.linalg.norm(a - b, axis=(0, 1))  # noqa: E731
                                    / np.linalg.norm(b, axis=(0, 1))))
    p_o, p_e = res.sys_discrete.poles(), sys_era.poles()
    p_t = np.exp(sys_true.poles() / FS)
    match = lambda a, b: float(np.max((c := np.abs(a[:, None] - b[None, :]))  # noqa: E731
                                      [linear_sum_assignment(c)]))
    auto = realize_steps(t, steps, n_block_rows=ROWS, n_block_cols=cols).order
    label = f"{label}, {ROWS}x{cols} blocks"
    print(f"\n[{label}]")
    print(f"  realize_steps         : {1e3 * t_ours:8.2f} ms (best of {REPEATS}), "
          f"order=None picks {auto}")
    print(f"  eigensys_realization  : {1e3 * t_era:8.2f} ms (best of {REPEATS})")
    print(f"  ratio ours / control  : {t_ours / t_era:8.2f}")
    print(f"  max rel. FRF diff ours vs control : {rel(G_ours, G_era):.2e}")
    print(f"  max rel. FRF error vs truth       : ours {rel(G_ours, G_true):.2e}, "
          f"control {rel(G_era, G_true):.2e}")
    print(f"  max |z-pole diff| ours vs control : {match(p_o, p_e):.2e}; vs truth: ours "
          f"{match(p_o, p_t):.2e}, control {match(p_e, p_t):.2e}")
    return (f"| {label} | {1e3 * t_ours:.2f} | {1e3 * t_era:.2f} | {t_ours / t_era:.2f} | "
            f"{rel(G_ours, G_era):.1e} | {match(p_o, p_e):.1e} | {rel(G_ours, G_true):.1e} | "
            f"{rel(G_era, G_true):.1e} |")


def main() -> None:
    sys_true = truth()
    t = np.arange(N_T) / FS
    steps = control.step_response(control.c2d(sys_true, 1 / FS), t).outputs.transpose(2, 0, 1)
    noise = 1e-5 * np.abs(steps).max() * np.random.default_rng(1).normal(size=steps.shape)
    print(f"2 in / 2 out, order {ORDER}, n_t={N_T}, fs={FS:g} Hz, Hankel {ROWS} block rows; "
          f"control {control.__version__}")
    rows = [compare("exact steps", t, steps, sys_true),
            compare("steps + 1e-5 noise", t, steps + noise, sys_true),
            compare("exact steps", t, steps, sys_true, cols=ROWS)]
    print("\n### Realisation benchmark (2x2, order 16, 2000 samples, 100 block rows)\n")
    print("| case | realize_steps [ms] | eigensys_realization [ms] | ratio | FRF diff | "
          "z-pole diff | FRF err ours | FRF err control |")
    print("|---|---|---|---|---|---|---|---|")
    print("\n".join(rows))
    print("\nrealize_steps timing includes the logm conversion to continuous time and the "
          "step-response fit; eigensys_realization returns the discrete model only.")
    threads(t, steps)


def threads(t: np.ndarray, steps: np.ndarray) -> None:
    """Issue 11: the wide case by default against one BLAS thread, and the SVD the old route
    ran with the default threads (two on this machine fight over two cores)."""
    from threadpoolctl import threadpool_info, threadpool_limits

    n_blas = max((p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"),
                 default=1)
    kw = dict(n_block_rows=ROWS, n_block_cols=COLS)
    t_def, _ = best_time(lambda: realize_steps(t, steps, ORDER, **kw))
    with threadpool_limits(limits=1, user_api="blas"):
        t_one, _ = best_time(lambda: realize_steps(t, steps, ORDER, **kw))
    h = np.diff(steps, axis=0, prepend=np.zeros((1, 2, 2)))
    idx = np.arange(ROWS)[:, None] + np.arange(1, COLS + 1)[None, :]
    hankel = h[idx].transpose(0, 2, 1, 3).reshape(ROWS * 2, COLS * 2)
    t_svd_def, _ = best_time(lambda: np.linalg.svd(hankel, full_matrices=False))
    with threadpool_limits(limits=1, user_api="blas"):
        t_svd_one, _ = best_time(lambda: np.linalg.svd(hankel, full_matrices=False))
    print(f"\nwide case ({ROWS} x {COLS} blocks), BLAS threads available: {n_blas}")
    print(f"  realize_steps, default settings : {1e3 * t_def:8.2f} ms")
    print(f"  realize_steps, one BLAS thread  : {1e3 * t_one:8.2f} ms  -> default / one-thread "
          f"= {t_def / t_one:.2f} (target <= 2)")
    print(f"  the Hankel SVD alone, default threads {1e3 * t_svd_def:.1f} ms, one thread "
          f"{1e3 * t_svd_one:.1f} ms (the old route ran it with the default threads)")


if __name__ == "__main__":
    main()
