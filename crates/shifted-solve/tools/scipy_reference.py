"""scipy/SuperLU reference timing for docs/BENCHMARKS.md: r_16(t B^-1 L) f, all 8 poles of degree 16,
one right-hand side, t = 0.01, factorization included (best of 3).

    cargo run --release -p shifted-solve --example timing -- 5 --dump /tmp   # writes /tmp/solve_{L,B}5.txt
    python3 crates/shifted-solve/tools/scipy_reference.py 5

(needs numpy and scipy)
"""
import sys, time, numpy as np, scipy.sparse as sp, scipy.sparse.linalg as sla
poles = [(-6.4161776990994341857, 1.1941223933701386699), (-5.9481522689511774823, 3.5874573620183223162),
 (-4.9931747377179964192, 5.9968817136039421951), (-3.5091036084149180718, 8.4361989858843750942),
 (-1.4193758971856659905, 1.0925363484496722585e1), (1.4139284624888862117, 1.3497725698892745388e1),
 (5.2649713434426468908, 1.6220221473167927305e1), (1.0843917078696988026e1, 1.9277446167181652284e1)]
for level in sys.argv[1:]:
    def load(name):
        d = np.loadtxt(f"/tmp/solve_{name}{level}.txt")
        n = int(d[:, 0].max()) + 1
        return sp.csc_matrix((d[:, 2], (d[:, 0].astype(int), d[:, 1].astype(int))), shape=(n, n))
    L, B = load("L"), load("B")
    n = L.shape[0]
    f = ((np.arange(n) * 7919) % 1000) / 1000.0 - 0.5
    t = 0.01
    best = 1e9
    for rep in range(3):
        t0 = time.perf_counter()
        bf = B @ f
        for (p, q) in poles:
            lu = sla.splu((t * L - complex(p, q) * B).tocsc())
            g = lu.solve(bf.astype(complex))
        best = min(best, time.perf_counter() - t0)
    print(f"n={n}: scipy splu all 8 poles deg16 1 rhs: best of 3 = {best:.3f} s")
