#!/usr/bin/env python3
"""Peer benchmark for cliffmap's parameterization: libigl SLIM, ARAP and LSCM.

Usage: python3 benches/peers/param_libigl.py OUT_DIR [--plot PNG] [--bench PATH_TO_param_bench]
       (OUT_DIR from examples/param_bench.rs, grid cells, or examples/param_store_bench.rs,
       real TIN cells read from stores: cells named tin_<store>_<cell id>, grouped per store)
       python3 benches/peers/param_libigl.py OUT_DIR --replot PNG   (redraw from OUT_DIR/peers.json)

With --bench, our default configuration is also timed per cell inside this run
(param_bench --time-obj), interleaved with the peers, so machine load affects both alike.

OUT_DIR is the directory written by `cargo run --release --example param_bench -- OUT_DIR`:
it holds cells/*.obj (v, vt = our chart, f) and ours.json (our timings and metrics).
Runs the peers on the same meshes, computes the SAME metrics in numpy for every method
(including ours, from the OBJ's vt, as a cross-check of the Rust metrics) and prints them
side by side. Times are medians of 3 runs, wall clock, single process.
"""
import glob
import json
import os
import sys
import time

import numpy as np
import igl

BENCH = None


def group_of(c):
    """Summary group of a cell: the store for TIN cells (tin_<store>_<id>), else the grid size."""
    if c.startswith("tin_"):
        return c.split("_")[1]
    return c.split("_")[3] if c.startswith("engabreen") else c.split("_")[-1]


def group_key(s):
    return (0, int(s), s) if s.isdigit() else (1, 0, s)


def read_obj(path):
    v, vt, f = [], [], []
    with open(path) as fh:
        for line in fh:
            p = line.split()
            if not p:
                continue
            if p[0] == "v":
                v.append([float(x) for x in p[1:4]])
            elif p[0] == "vt":
                vt.append([float(x) for x in p[1:3]])
            elif p[0] == "f":
                f.append([int(x.split("/")[0]) - 1 for x in p[1:4]])
    return np.array(v), np.array(vt), np.array(f, dtype=np.int64)


def metrics(V, F, UV):
    """Flips, mean |log area|, mean s1/s2, mean symmetric Dirichlet (3D-area weighted),
    with the UVs scaled so the total UV area equals the total 3D area. A chart that is
    mirrored as a whole is not counted as flipped: flips = triangles of the minority
    orientation (zero area counts as flipped)."""
    p0, p1, p2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e1, e2 = p1 - p0, p2 - p0
    a3 = 0.5 * np.linalg.norm(np.cross(e1, e2), axis=1)
    l1 = np.linalg.norm(e1, axis=1)
    x = e1 / l1[:, None]
    n = np.cross(e1, e2)
    n /= np.linalg.norm(n, axis=1)[:, None]
    y = np.cross(n, x)
    # 3D triangle in its own frame: q0 = 0, q1 = (l1, 0), q2 = (e2.x, e2.y)
    Q = np.zeros((len(F), 2, 2))
    Q[:, 0, 0] = l1
    Q[:, 0, 1] = np.sum(e2 * x, axis=1)
    Q[:, 1, 1] = np.sum(e2 * y, axis=1)
    u0, u1, u2 = UV[F[:, 0]], UV[F[:, 1]], UV[F[:, 2]]
    Um = np.stack([u1 - u0, u2 - u0], axis=2)  # (F, 2, 2): columns are edge vectors
    signed = 0.5 * (Um[:, 0, 0] * Um[:, 1, 1] - Um[:, 0, 1] * Um[:, 1, 0])
    pos = np.sum(signed > 0)
    neg = np.sum(signed < 0)
    zero = np.sum(signed == 0)
    flips = int(min(pos, neg) + zero)
    k = np.sqrt(a3.sum() / np.abs(signed).sum())
    J = k * Um @ np.linalg.inv(Q)
    s = np.linalg.svd(J, compute_uv=False)
    s1, s2 = s[:, 0], s[:, 1]
    w = a3 / a3.sum()
    with np.errstate(divide="ignore", invalid="ignore"):
        return {
            "flipped": flips,
            "area": float(np.sum(w * np.abs(np.log(s1 * s2)))),
            "angle": float(np.sum(w * s1 / s2)),
            "symd": float(np.sum(w * (s1**2 + s2**2 + 1 / s1**2 + 1 / s2**2))),
        }


def ratios(m, ref):
    """Excess symmetric Dirichlet, area distortion and angle excess (s1/s2 - 1), each
    divided by the reference's."""
    q = lambda a, b: a / b if b > 0 else float("inf") if a > 0 else 1.0
    return (q(m["symd"] - 4.0, ref["symd"] - 4.0), q(m["area"], ref["area"]), q(m["angle"] - 1.0, ref["angle"] - 1.0))


def tutte(V, F):
    bnd = igl.boundary_loop(F).astype(np.int32)
    bnd_uv = igl.map_vertices_to_circle(V, bnd)
    uv = igl.harmonic(V, F, bnd.astype(np.int64), bnd_uv, 1)
    # Scale the initial layout to the 3D area (libigl ARAP flips at terrain scale otherwise).
    a3 = igl.doublearea(V, F).sum()
    auv = np.abs(igl.doublearea(uv, F)).sum()
    return uv * np.sqrt(a3 / auv)


def run_slim(V, F, iters):
    uv = tutte(V, F)
    data = igl.slim_precompute(V, F.astype(np.int32), uv, igl.MappingEnergyType.SYMMETRIC_DIRICHLET,
                               np.zeros(0, dtype=np.int32), np.zeros((0, 2)), 0.0)
    return igl.slim_solve(data, iters)


def run_arap(V, F):
    uv = tutte(V, F)
    data = igl.ARAPData()
    data.with_dynamics = True
    data.max_iter = 100
    b = np.zeros(0, dtype=np.int32)
    igl.arap_precomputation(V, F, 2, b, data)
    return igl.arap_solve(np.zeros((0, 2)), data, uv)


def run_lscm(V, F):
    bnd = igl.boundary_loop(F)
    b = np.array([bnd[0], bnd[len(bnd) // 2]], dtype=np.int64)
    uv, _ = igl.lscm(V, F, b, np.array([[0.0, 0.0], [1.0, 0.0]]))
    return uv


def timed(fn, reps=3):
    ts, out = [], None
    for _ in range(reps):
        t = time.perf_counter()
        out = fn()
        ts.append((time.perf_counter() - t) * 1e3)
    return float(np.median(ts)), out


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        sys.exit(2)
    out = sys.argv[1]
    if "--replot" in sys.argv:
        # Only redraw the plot from OUT_DIR/peers.json of an earlier run.
        make_plot(json.load(open(os.path.join(out, "peers.json"))), sys.argv[sys.argv.index("--replot") + 1])
        return
    global BENCH
    BENCH = None
    if "--bench" in sys.argv:
        BENCH = sys.argv[sys.argv.index("--bench") + 1]
    plot = None
    if "--plot" in sys.argv:
        plot = sys.argv[sys.argv.index("--plot") + 1]
    ours = json.load(open(os.path.join(out, "ours.json")))
    by = {(r["cell"], r["config"]): r for r in ours}
    rows = []
    hdr = (f"{'cell':<32} {'tris':>6} {'method':<22} {'ms':>8} {'÷SLIM50':>6} {'flip':>5} {'|logA|':>8} {'s1/s2':>8} "
           f"{'symD-4':>9} {'ex÷ref':>7} {'A÷ref':>7} {'ang÷ref':>7}")
    print("ref = SLIM 200 it (converged); ex = symD - 4; A = mean |ln A|; ang = mean s1/s2 - 1; ms ÷ SLIM 50 it")
    print(hdr)
    for path in sorted(glob.glob(os.path.join(out, "cells", "*.obj"))):
        cell = os.path.basename(path)[:-4]
        V, TC, F = read_obj(path)
        V = V - V.mean(axis=0)
        res = []
        for name, cfg in sorted(by):
            if name == cell and cfg != "orthographic" and "ms_median" in by[(name, cfg)]:
                r = by[(name, cfg)]
                m = r["metrics"]
                res.append((f"ours {cfg}", r["ms_median"], {"flipped": m["flipped"], "area": m["area_distortion_mean"],
                                                           "angle": m["angle_distortion_mean"], "symd": m["symmetric_dirichlet_mean"]}))
        res.append(("ours default (numpy)", by[(cell, "default")]["ms_median"], metrics(V, F, TC)))
        if BENCH:
            # Our default options timed again here, interleaved with the peers (same load).
            import subprocess
            o = json.loads(subprocess.run([BENCH, "--time-obj", path, "3"], check=True, capture_output=True, text=True).stdout)
            m = o["metrics"]
            res.append(("ours default, same run", o["ms_median"], {"flipped": m["flipped"], "area": m["area_distortion_mean"],
                                                                  "angle": m["angle_distortion_mean"], "symd": m["symmetric_dirichlet_mean"]}))
        for it in (5, 20, 50):
            ms, uv = timed(lambda: run_slim(V, F, it))
            res.append((f"SLIM {it} it", ms, metrics(V, F, uv)))
        # The converged reference: SLIM with 200 iterations (timed once).
        ms, uv = timed(lambda: run_slim(V, F, 200), reps=1)
        res.append(("SLIM 200 it", ms, metrics(V, F, uv)))
        ms, uv = timed(lambda: run_arap(V, F))
        res.append(("ARAP 100 it", ms, metrics(V, F, uv)))
        ms, uv = timed(lambda: run_lscm(V, F))
        res.append(("LSCM", ms, metrics(V, F, uv)))
        ref = [r for r in res if r[0] == "SLIM 200 it"][0][2]
        ref_ms = [r for r in res if r[0] == "SLIM 50 it"][0][1]
        for name, ms, m in res:
            r_ex, r_area, r_ang = ratios(m, ref)
            print(f"{cell:<32} {len(F):>6} {name:<22} {ms:>8.1f} {ms / ref_ms:>6.2f} {m['flipped']:>5} {m['area']:>8.4f} "
                  f"{m['angle']:>8.4f} {m['symd'] - 4.0:>9.4f} {r_ex:>7.3f} {r_area:>7.3f} {r_ang:>7.3f}")
            rows.append({"cell": cell, "triangles": int(len(F)), "method": name, "ms": ms, **m})
        print()
    json.dump(rows, open(os.path.join(out, "peers.json"), "w"), indent=1)
    # Summary: per method and group, median time and median / worst ratios to converged SLIM.
    print("summary (median over cells): method, group, ms, ms/SLIM50, excess/area/angle-excess ÷ SLIM 200 it (median, worst), max flips")
    sizes = sorted({group_of(r["cell"]) for r in rows}, key=group_key)
    ref = {r["cell"]: r for r in rows if r["method"] == "SLIM 200 it"}
    ref_ms = {r["cell"]: r["ms"] for r in rows if r["method"] == "SLIM 50 it"}
    methods = []
    for r in rows:
        if r["method"] not in methods:
            methods.append(r["method"])
    for s in sizes + ["all"]:
        for meth in methods:
            sel = [r for r in rows if r["method"] == meth and (s == "all" or group_of(r["cell"]) == s)]
            if not sel:
                continue
            ms = float(np.median([r["ms"] for r in sel]))
            tr = float(np.median([r["ms"] / ref_ms[r["cell"]] for r in sel]))
            rs = np.array([ratios(r, ref[r["cell"]]) for r in sel])
            med, worst = np.median(rs, axis=0), np.max(rs, axis=0)
            fl = int(max(r["flipped"] for r in sel))
            print(f"  {s:>11} {meth:<22} {ms:>8.1f} ms {tr:>5.2f}x  excess {med[0]:.3f}/{worst[0]:.3f}  "
                  f"area {med[1]:.3f}/{worst[1]:.3f}  angle {med[2]:.3f}/{worst[2]:.3f}  flips {fl}")
    if plot:
        make_plot(rows, plot)


def make_plot(rows, plot):
    """Median over cells of the excess symmetric Dirichlet energy (symD - 4, 0 = isometric)
    against the median time, per method, one panel per grid size."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    size_of = group_of
    sizes = sorted({size_of(r["cell"]) for r in rows}, key=group_key)
    keep = ["ours default, same run", "ours tol=1e-2,sweeps=2", "ours tol=1e-3,sweeps=8", "ours tol=1e-5,sweeps=64",
            "ours theta=3", "SLIM 5 it", "SLIM 20 it", "SLIM 50 it", "ARAP 100 it", "LSCM"]
    fig, axes = plt.subplots(1, len(sizes), figsize=(6.5 * len(sizes), 4.8))
    if len(sizes) == 1:
        axes = [axes]
    for ax, s in zip(axes, sizes):
        for meth in keep:
            sel = [r for r in rows if r["method"] == meth and size_of(r["cell"]) == s]
            if not sel:
                continue
            ms = float(np.median([r["ms"] for r in sel]))
            ex = float(np.median([max(r["symd"] - 4.0, 1e-6) for r in sel]))
            ours = meth.startswith("ours")
            ax.scatter([ms], [ex], marker="o" if ours else "s", s=40, color="tab:blue" if ours else "tab:red")
            ax.annotate(meth.replace("ours ", "ours\n").replace(", same run", ""), (ms, ex), fontsize=7,
                        xytext=(4, 2), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("median time per cell [ms] (same run, 2-core VM)")
        ax.set_ylabel("median excess symmetric Dirichlet (symD - 4)")
        ncell = len({r["cell"] for r in rows if size_of(r["cell"]) == s})
        if s.isdigit():
            ax.set_title(f"{s}x{s} grid cells ({2 * (int(s) - 1) ** 2} triangles), {ncell} cells")
        else:
            ax.set_title(f"TIN cells of the {s} store, {ncell} cells")
        ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(plot, dpi=110)
    print(f"wrote {plot}")


if __name__ == "__main__":
    main()
