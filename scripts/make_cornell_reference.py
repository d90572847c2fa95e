#!/usr/bin/env python3
"""Regenerate tests/data/cornell-lights-reference.json: an independent reference of
scenes/cornell-lights.gltf rendered by Mitsuba 3 (the export of `lanterna scene
export-mitsuba`), as per-block means and standard errors over independent runs.

Usage: scripts/make_cornell_reference.py [--lanterna target/release/lanterna]
"""
import argparse, json, os, subprocess, tempfile

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lanterna", default="target/release/lanterna")
    ap.add_argument("--size", type=int, default=16)
    ap.add_argument("--block", type=int, default=4)
    ap.add_argument("--runs", type=int, default=16)
    ap.add_argument("--spp", type=int, default=4096)
    ap.add_argument("--max-depth", type=int, default=4)
    ap.add_argument("-o", default="tests/data/cornell-lights-reference.json")
    a = ap.parse_args()
    import numpy as np
    import mitsuba as mi
    try:
        mi.set_variant("llvm_ad_rgb")
    except Exception:
        mi.set_variant("scalar_rgb")
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "export")
        subprocess.run([a.lanterna, "scene", "export-mitsuba", "scenes/cornell-lights.gltf", "-o", out,
                        "--width", str(a.size), "--height", str(a.size), "--max-depth", str(a.max_depth)], check=True)
        manifest = json.load(open(os.path.join(out, "lanterna_export.json")))
        scene = mi.load_file(os.path.join(out, "scene.xml"))
        n = a.size // a.block
        runs = []
        for r in range(a.runs):
            img = np.array(mi.render(scene, spp=a.spp, seed=r))[:, :, :3].astype(np.float64)
            runs.append(img.reshape(n, a.block, n, a.block, 3).mean(axis=(1, 3)))
    runs = np.stack(runs)
    mean = runs.mean(0)
    stderr = runs.std(0, ddof=1) / np.sqrt(a.runs)
    json.dump({
        "scene": "scenes/cornell-lights.gltf",
        "scene_hash": manifest.get("scene_hash"),
        "renderer": f"Mitsuba {mi.__version__} ({mi.variant()}), path integrator, box filter",
        "width": a.size, "height": a.size, "max_depth": a.max_depth, "block": a.block,
        "runs": a.runs, "spp_per_run": a.spp,
        "block_mean": mean.tolist(), "block_stderr": stderr.tolist(),
    }, open(a.o, "w"), indent=1)
    print(f"wrote {a.o}: mean {mean.mean(axis=(0, 1))}")

if __name__ == "__main__":
    main()
