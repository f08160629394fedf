#!/usr/bin/env python3
"""Markdown tables for docs/parameterization.md from a benchmark directory.

Usage: python3 benches/peers/param_tables.py OUT_DIR
OUT_DIR holds ours.json (examples/param_bench.rs or examples/param_store_bench.rs) and
peers.json (benches/peers/param_libigl.py run on it; without it only table 1). Prints
1. the configuration table of our knobs (ours.json alone),
2. the per-cell table against SLIM 200 it (converged), SLIM 5/50 it, ARAP and LSCM,
3. the summary per group (grid size or store) and over all cells.
Distortion is reported as excess over an isometry: symD - 4, mean |ln A|, mean s1/s2 - 1.
"""
import json
import os
import statistics as st
import sys

sys.path.insert(0, os.path.dirname(__file__))
from param_libigl import group_key, group_of, ratios  # noqa: E402


def q(a, b):
    return a / b if b > 1e-4 else None


def fmt(x, spec=".3f"):
    return "–" if x is None else format(x, spec)


def main():
    out = sys.argv[1]
    ours = json.load(open(os.path.join(out, "ours.json")))
    peers_path = os.path.join(out, "peers.json")
    peers = json.load(open(peers_path)) if os.path.exists(peers_path) else None
    cfgs = {}
    for r in ours:
        if "metrics" in r and r.get("config"):
            cfgs.setdefault(r["config"], []).append(r)
    default = {r["cell"]: r for r in cfgs["default"]}
    groups = sorted({group_of(c) for c in default}, key=group_key)

    print("### Our knobs (median over the cells of each group; excess ratios to the default, per cell)\n")
    head = "| config | " + " | ".join(f"median ms, {g}" for g in groups)
    print(head + " | excess ÷ default, median / worst | median mean \\|ln A\\| | median mean s1/s2 | max flips |")
    print("|---|" + "---|" * len(groups) + "---|---|---|---|")
    for name, rs in cfgs.items():
        ms = [fmt(st.median([r["ms_median"] for r in rs if group_of(r["cell"]) == g and "ms_median" in r]), ".0f")
              if any(group_of(r["cell"]) == g and "ms_median" in r for r in rs) else "-" for g in groups]
        ex = [q(r["metrics"]["symmetric_dirichlet_mean"] - 4, default[r["cell"]]["metrics"]["symmetric_dirichlet_mean"] - 4)
              for r in rs if r["cell"] in default]
        ex = [x for x in ex if x is not None]
        area = st.median([r["metrics"]["area_distortion_mean"] for r in rs])
        ang = st.median([r["metrics"]["angle_distortion_mean"] for r in rs])
        fl = max(r["metrics"]["flipped"] for r in rs)
        exs = f"{st.median(ex):.3f} / {max(ex):.3f}" if ex else "–"
        print(f"| {name} | " + " | ".join(ms) + f" | {exs} | {area:.4f} | {ang:.4f} | {fl} |")

    if peers is None:
        print(f"\n(no {peers_path}: run benches/peers/param_libigl.py for the peer tables)")
        return
    by = {}
    for r in peers:
        by.setdefault(r["cell"], {})[r["method"]] = r
    print("\n### Per cell\n")
    print("| cell | triangles | ours ms | ours flips / excess / \\|ln A\\| / s1/s2 | ours ÷ SLIM-200: excess / area / angle excess "
          "| ours ms ÷ SLIM-50 ms | SLIM 5 it ms / flips / excess | SLIM 50 it ms / excess | SLIM 200 it ms / flips / excess "
          "| ARAP ms / flips / excess | LSCM ms / flips / excess |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for c in sorted(by):
        m = by[c]
        o, r, s5, s50, a, l = (m[k] for k in ("ours default, same run", "SLIM 200 it", "SLIM 5 it", "SLIM 50 it", "ARAP 100 it", "LSCM"))
        ex = lambda x: x["symd"] - 4  # noqa: E731
        rx = (q(ex(o), ex(r)), q(o["area"], r["area"]), q(o["angle"] - 1, r["angle"] - 1))
        print(f"| {c.removeprefix('tin_')} | {o['triangles']} | {o['ms']:.0f} | {o['flipped']} / {ex(o):.4g} / {o['area']:.4f} / "
              f"{o['angle']:.4f} | {fmt(rx[0])} / {fmt(rx[1])} / {fmt(rx[2])} | {o['ms'] / s50['ms']:.2f} | "
              f"{s5['ms']:.0f} / {s5['flipped']} / {ex(s5):.4g} | {s50['ms']:.0f} / {ex(s50):.4g} | "
              f"{r['ms']:.0f} / {r['flipped']} / {ex(r):.4g} | {a['ms']:.0f} / {a['flipped']} / {ex(a):.4g} | "
              f"{l['ms']:.0f} / {l['flipped']} / {ex(l):.4g} |")

    print("\n### Summary (median / worst over the cells whose converged SLIM excess is > 1e-4; "
          "ratios to SLIM 200 it; ms ÷ SLIM-50 per cell, median)\n")
    print("| group | method | median ms | ms ÷ SLIM-50 | excess ÷ SLIM | area ÷ SLIM | angle excess ÷ SLIM | max flips |")
    print("|---|---|---|---|---|---|---|---|")
    ref = {c: m["SLIM 200 it"] for c, m in by.items()}
    ref_ms = {c: m["SLIM 50 it"]["ms"] for c, m in by.items()}
    keep = ["ours default, same run", "SLIM 5 it", "SLIM 20 it", "SLIM 50 it", "SLIM 200 it", "ARAP 100 it", "LSCM"]
    for g in groups + ["all"]:
        for meth in keep:
            sel = [m[meth] for c, m in by.items() if meth in m and (g == "all" or group_of(c) == g)]
            if not sel:
                continue
            ms = st.median([r["ms"] for r in sel])
            tr = st.median([r["ms"] / ref_ms[r["cell"]] for r in sel])
            rs = [ratios(r, ref[r["cell"]]) for r in sel if ref[r["cell"]]["symd"] - 4 > 1e-4]
            cols = []
            for k in range(3):
                v = [x[k] for x in rs]
                cols.append(f"{st.median(v):.3f} / {max(v):.3f}" if v else "–")
            fl = max(r["flipped"] for r in sel)
            print(f"| {g} | {meth} | {ms:.0f} | {tr:.2f} | {cols[0]} | {cols[1]} | {cols[2]} | {fl} |")


if __name__ == "__main__":
    main()
