#!/usr/bin/env python3
"""Point-cloud Laplacians side by side (issue #27), in one run: wfem's `cloud_bench` example
(mesh_fem::assemble_cloud, then wfem_heat::HeatKernel) against robust_laplacian's
`point_cloud_laplacian`, each in fresh processes through `peers.py measure` (best wall time
and its peak RSS), on clouds sampled uniformly from the unit sphere. Prints a Markdown table.

    cargo build --release -p wfem-heat --example cloud_bench
    python3 benches/peers/clouds.py --sizes 100000 1000000 --repeat 1

Needs numpy and robust_laplacian==1.1.0 (benches/peers/requirements.txt).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def measure(cmd, repeat):
    out = subprocess.run(
        [sys.executable, os.path.join(HERE, "peers.py"), "measure", "--repeat", str(repeat), "--"] + cmd,
        capture_output=True,
        text=True,
        check=True,
    )
    v = json.loads(out.stdout)
    if "error" in v:
        raise RuntimeError(v["error"])
    best = min(range(len(v["wall"])), key=lambda i: v["wall"][i])
    last = [line for line in v["stdout"].splitlines() if line.startswith("{")][-1]
    return v["wall"][best], v["maxrss_bytes"][best], json.loads(last)


def main():
    import numpy as np

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100_000, 1_000_000])
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--t", type=float, default=0.01)
    parser.add_argument("--bench", default=os.path.join(ROOT, "target/release/examples/cloud_bench"))
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.sizes:
            rng = np.random.default_rng(n)
            p = rng.normal(size=(n, 3))
            p /= np.linalg.norm(p, axis=1)[:, None]
            path = os.path.join(tmp, f"sphere{n}.npy")
            np.save(path, p)
            ours = measure([args.bench, "heat-cloud", path, str(args.t)], args.repeat)
            peer = measure([sys.executable, os.path.join(HERE, "peers.py"), "cloud-laplacian", path], args.repeat)
            mesh = measure([args.bench, "heat-mesh", str(n), str(args.t)], args.repeat)
            rows.append((n, ours, peer, mesh))
            print(f"{n}: wfem {ours[2]}, robust_laplacian {peer[2]}, mesh {mesh[2]}", file=sys.stderr)
    print("| points | L, B, D: wfem | L, M: robust_laplacian | ratio | peak RSS wfem / robust_laplacian | K_t f on the cloud | K_t f on a torus mesh of n vertices | ratio |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n, ours, peer, mesh in rows:
        a, b = ours[2]["kernel_seconds"], peer[2]["kernel_seconds"]
        hc, hm = ours[2]["heat_seconds"], mesh[2]["heat_seconds"]
        print(
            f"| {n:,} | {a:.2f} s | {b:.2f} s | {b / a:.1f}× | {ours[1] / 2**30:.2f} / {peer[1] / 2**30:.2f} GiB "
            f"| {hc:.2f} s | {hm:.2f} s | {hc / hm:.2f} |"
        )


if __name__ == "__main__":
    main()
