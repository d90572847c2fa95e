#!/usr/bin/env python3
"""Independent reference for lanterna's conformance suite (tests/conformance.rs).

Renders a scene exported by `lanterna scene export-mitsuba` with Mitsuba 3's `path`
integrator and writes, as JSON, per block of BLOCK×BLOCK pixels and per channel the mean
over independent runs and its standard error, and the same for the whole image.

Each run is the image at the export's max_depth minus the image at max_depth 1 with the
same seed: the camera rays of both are identical, so emission seen directly cancels
exactly, and what remains is all light that reached a surface — the part every NEE and
MIS defect changes. lanterna's `--hide-emitters` renders the same quantity. (Mitsuba's
own `hide_emitters` means something else: emitters become invisible to camera rays.)

Usage:
  conformance_reference.py EXPORT_DIR -o OUT.json [--runs 16] [--spp 1024] [--block 8]

Exit status 0 on success, 2 on bad input.
"""

import argparse
import json
import os
import sys

LLVM_PATHS = [
    "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1",
    "/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("export_dir")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--runs", type=int, default=16)
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--block", type=int, default=8)
    a = ap.parse_args()
    manifest_path = os.path.join(a.export_dir, "lanterna_export.json")
    if not os.path.exists(manifest_path):
        print(f"{manifest_path}: not found (run lanterna scene export-mitsuba)", file=sys.stderr)
        sys.exit(2)
    manifest = json.load(open(manifest_path))
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        for p in LLVM_PATHS:
            if os.path.exists(p):
                os.environ["DRJIT_LIBLLVM_PATH"] = p
                break
    import numpy as np
    import mitsuba as mi

    try:
        mi.set_variant("llvm_ad_rgb")
    except Exception:
        mi.set_variant("scalar_rgb")
    xml = os.path.join(a.export_dir, "scene.xml")
    depth = int(manifest["max_depth"])
    full = mi.load_file(xml, max_depth=depth)
    direct_view = mi.load_file(xml, max_depth=1)
    w, h, b = manifest["width"], manifest["height"], a.block
    bx, by = -(-w // b), -(-h // b)
    blocks, means = [], []
    for r in range(a.runs):
        img = np.array(mi.render(full, spp=a.spp, seed=r), dtype=np.float64)[:, :, :3]
        img -= np.array(mi.render(direct_view, spp=a.spp, seed=r), dtype=np.float64)[:, :, :3]
        means.append(img.mean(axis=(0, 1)))
        blk = np.zeros((by, bx, 3))
        for j in range(by):
            for i in range(bx):
                blk[j, i] = img[j * b:(j + 1) * b, i * b:(i + 1) * b].mean(axis=(0, 1))
        blocks.append(blk)
    blocks, means = np.stack(blocks), np.stack(means)
    n = a.runs
    out = {
        "renderer": f"Mitsuba {mi.__version__} ({mi.variant()}), path integrator, "
                    f"max_depth {depth} minus max_depth 1 (same seeds)",
        "scene_hash": manifest.get("scene_hash"),
        "width": w, "height": h, "max_depth": depth, "block": b,
        "runs": n, "spp_per_run": a.spp,
        "mean": means.mean(0).tolist(),
        "mean_stderr": (means.std(0, ddof=1) / np.sqrt(n)).tolist(),
        "block_mean": blocks.mean(0).tolist(),
        "block_stderr": (blocks.std(0, ddof=1) / np.sqrt(n)).tolist(),
    }
    tmp = a.output + ".tmp"
    with open(tmp, "w") as f:
        json.dump(out, f, indent=1)
    os.replace(tmp, a.output)


if __name__ == "__main__":
    main()
