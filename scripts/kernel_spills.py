#!/usr/bin/env python3
"""Register pressure of the path-tracing kernel as lavapipe compiles it.

lavapipe (Mesa's CPU Vulkan driver) turns each compute pipeline into x86 code through
LLVM; with `GALLIVM_DEBUG=asm` it prints that code. This script renders one tiny image
per method with the shader cache off (so every pipeline is compiled and printed), finds
the kernels in the listing (the functions far larger than the driver's helpers), and
reports for each:

* instructions (static count: code size, not work done);
* the stack frame it reserves (`subq $N, %rsp`): per-lane arrays such as the traversal
  stack and the training records, plus LLVM's spill slots;
* spill stores and reloads: vector registers written to and read back from the stack
  (static counts). With AVX2 LLVM has 16 vector registers; every value live across the
  kernel's loops beyond those is spilled.

    scripts/kernel_spills.py [--lanterna target/release/lanterna] [--scene scenes/street.gltf]
                             [--method pt --method ris ...] [--json out.json]

Only lavapipe prints this; on other devices the listing is empty and the script says so.
"""

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

LABEL = re.compile(r"^([A-Za-z_][\w.]*):$")
INSN = re.compile(r"^\s+([0-9a-f]+):\t(.*)$")  # offset, instruction
FRAME = re.compile(r"subq\s+\$(\d+), %rsp")
# A vector register stored to / loaded from a stack slot (rsp- or rbp-relative, no index).
SPILL_STORE = re.compile(r"^v?mov\w*\s+%[xy]mm\d+, -?\d*\(%r[sb]p\)$")
SPILL_LOAD = re.compile(r"^v?mov\w*\s+-?\d*\(%r[sb]p\), %[xy]mm\d+$")
# Kernels are tens of thousands of instructions; the driver's helpers a few hundred.
KERNEL_MIN_INSTRUCTIONS = 2000


def functions(listing):
    """(name, [(offset, instruction text)]) for every function of a GALLIVM_DEBUG=asm
    listing (offsets from the function's start)."""
    out = []
    for line in listing.splitlines():
        m = LABEL.match(line)
        if m:
            out.append((m.group(1), []))
            continue
        m = INSN.match(line)
        if m and out:
            out[-1][1].append((int(m.group(1), 16), m.group(2).strip()))
    return out


def measure(instructions):
    frame = 0
    for i in instructions[:64]:
        m = FRAME.search(i)
        if m:
            frame = int(m.group(1))
            break
    stores = sum(1 for i in instructions if SPILL_STORE.match(i))
    loads = sum(1 for i in instructions if SPILL_LOAD.match(i))
    return {
        "instructions": len(instructions),
        "stack_frame_bytes": frame,
        "spill_stores": stores,
        "spill_reloads": loads,
    }


def kernels_of(lanterna, scene, method, extra):
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, GALLIVM_DEBUG="asm", MESA_SHADER_CACHE_DISABLE="true")
        cmd = [lanterna, "render", scene, "--method", method, "--spp", "1", "--width", "8",
               "--height", "8", "--quiet", "--no-png", "-o", os.path.join(tmp, "k.exr")] + extra
        p = subprocess.run(cmd, env=env, capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr[-2000:]}")
        listing = p.stdout + "\n" + p.stderr
    return [(name, measure([text for _, text in ins])) for name, ins in functions(listing)
            if len(ins) >= KERNEL_MIN_INSTRUCTIONS]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--lanterna", default="target/release/lanterna")
    ap.add_argument("--scene", default="scenes/street.gltf")
    ap.add_argument("--method", action="append",
                    help="methods to compile (default: pt, ris, guided, guided-ris)")
    ap.add_argument("--json", help="also write the results here")
    ap.add_argument("extra", nargs="*", help="further `lanterna render` options (after --)")
    a = ap.parse_args()
    methods = a.method or ["pt", "ris", "guided", "guided-ris"]
    results = []
    for method in methods:
        found = kernels_of(a.lanterna, a.scene, method, a.extra)
        if not found:
            sys.exit("no kernel in the listing: is the device lavapipe (GALLIVM_DEBUG=asm)?")
        # Guided methods compile a training and a render variant; the listing does not
        # name them, so they are numbered in compile order.
        for k, (name, m) in enumerate(found):
            results.append(dict(method=method, kernel=k, function=name, **m))
    print(f"{'method':<11} {'#':>1} {'instructions':>12} {'stack frame':>12} {'spill stores':>12} {'reloads':>8}")
    for r in results:
        print(f"{r['method']:<11} {r['kernel']:>1} {r['instructions']:>12} {r['stack_frame_bytes']:>12} "
              f"{r['spill_stores']:>12} {r['spill_reloads']:>8}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
