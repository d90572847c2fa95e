#!/usr/bin/env python3
"""Where a lavapipe kernel spends its time, instruction by instruction.

lavapipe compiles each compute pipeline to x86 code at run time, so a profiler sees
anonymous addresses: `perf report` can only say "[JIT]". This script renders under
`perf record` with `GALLIVM_DEBUG=asm` and the shader cache off, so the same run both
samples the kernel and prints its code (offsets from the function's start), then places
each kernel's listing in memory: the load address is the one at which the most samples
fall on instruction boundaries (the right one puts nearly all of a kernel's samples
there; a wrong one about a quarter, by chance). It then prints the hottest windows of
instructions with their share of the kernel's samples and a summary of their opcodes,
and with --annotate writes the whole listing with a share per instruction.

    scripts/kernel_profile.py [--lanterna target/release/lanterna] [--scene scenes/cornell-lights.gltf]
                              [--method pt] [--spp 256] [--size 64x64] [--window 100] [--top 20]
                              [--annotate listing.txt] [-- further render options]

Needs `perf` (Debian: linux-perf) allowed to sample this process (perf_event_paranoid
≤ 2), and lavapipe as the device. Reading the listing: per-lane buffer loads appear as
runs of `cmpl`/`jae` (bounds check) + `movl`/`vpinsrd` per component and lane; divergent
control flow as `vptest`/`je` on the execution mask; spills as `vmovdqa` to and from
`(%rsp)`. Used for the profile notes in bench/README.md (2026-11-24).
"""

import argparse
import collections
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from kernel_spills import KERNEL_MIN_INSTRUCTIONS, functions  # noqa: E402
# gallivm's functions start 16-byte aligned.
ALIGN = 16
# gallivm's disassembler (lp_bld_debug.cpp) lists at most this many bytes of a function.
LISTING_LIMIT = 96 * 1024


def jit_samples(perf_data):
    """Instruction pointers of the samples taken in code no file backs (the JIT's)."""
    p = subprocess.run(["perf", "script", "-i", perf_data, "-F", "ip,dso"],
                       capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"perf script failed:\n{p.stderr[-2000:]}")
    ips = []
    for line in p.stdout.splitlines():
        parts = line.split(None, 1)
        if len(parts) != 2:
            continue
        dso = parts[1]
        if "perf-" in dso or "[unknown]" in dso or "JIT" in dso:
            ips.append(int(parts[0], 16))
    return ips


def place(kernel, ips):
    """The load address of `kernel` (a list of (offset, text)) that puts the most
    samples on its instruction boundaries, and how many it puts there."""
    offsets = {o for o, _ in kernel}
    size = kernel[-1][0] + 16
    hot = [ip for ip, _ in collections.Counter(ips).most_common(12)]
    probe = ips[:: max(1, len(ips) // 3000)]
    best = (0, None)
    for h in hot:
        for o in offsets:
            base = h - o
            if base % ALIGN:
                continue
            score = sum(1 for ip in probe if 0 <= ip - base < size and ip - base in offsets)
            if score > best[0]:
                best = (score, base)
    score, base = best
    if base is None:
        return None, 0
    return base, sum(1 for ip in ips if 0 <= ip - base < size and ip - base in offsets)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--lanterna", default="target/release/lanterna")
    ap.add_argument("--scene", default="scenes/cornell-lights.gltf")
    ap.add_argument("--method", default="pt")
    ap.add_argument("--spp", default="256")
    ap.add_argument("--size", default="64x64", help="image size WxH")
    ap.add_argument("--window", type=int, default=100, help="instructions per window")
    ap.add_argument("--top", type=int, default=20, help="windows to print")
    ap.add_argument("--annotate", help="write the hottest kernel's listing with shares here")
    ap.add_argument("extra", nargs="*", help="further `lanterna render` options (after --)")
    a = ap.parse_args()
    w, h = a.size.split("x")
    with tempfile.TemporaryDirectory() as tmp:
        data = os.path.join(tmp, "perf.data")
        env = dict(os.environ, GALLIVM_DEBUG="asm", MESA_SHADER_CACHE_DISABLE="true")
        cmd = ["perf", "record", "-q", "-F", "4000", "-o", data, "--",
               a.lanterna, "render", a.scene, "--method", a.method, "--spp", a.spp,
               "--width", w, "--height", h, "--quiet", "--no-png",
               "-o", os.path.join(tmp, "k.exr")] + a.extra
        p = subprocess.run(cmd, env=env, capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr[-2000:]}")
        listing = p.stdout + "\n" + p.stderr
        ips = jit_samples(data)
    kernels = [(n, ins) for n, ins in functions(listing) if len(ins) >= KERNEL_MIN_INSTRUCTIONS]
    if not kernels:
        sys.exit("no kernel in the listing: is the device lavapipe (GALLIVM_DEBUG=asm)?")
    if not ips:
        sys.exit("no samples in JIT code: is perf allowed to sample (perf_event_paranoid)?")
    print(f"{len(ips)} samples in JIT code; {len(kernels)} kernel(s) in the listing")
    placed = []
    for k, (name, ins) in enumerate(kernels):
        base, hits = place(ins, ips)
        print(f"kernel {k} ({name}, {len(ins)} instructions): "
              f"{hits} samples ({100 * hits / len(ips):.1f} % of JIT samples)"
              + (f" at {base:#x}" if base is not None else ", not found"))
        if base is not None and hits:
            placed.append((hits, k, ins, base))
    if not placed:
        sys.exit("no kernel could be placed: was it compiled in this run (shader cache off)?")
    hits, k, ins, base = max(placed)
    # gallivm's disassembler stops after 96 KiB of a function, so a larger kernel's
    # listing ends there while its code goes on: samples past the listing's end, up to
    # the next kernel, are the same kernel's (no other function there is that large).
    end = base + ins[-1][0] + 16
    if ins[-1][0] + 16 >= LISTING_LIMIT - 64:
        others = [b for _, kk, _, b in placed if kk != k and b > base]
        limit = min(others, default=end + (64 << 20))
        beyond = [ip for ip in ips if end <= ip < limit]
        if beyond:
            print(f"kernel {k}'s listing stops at gallivm's {LISTING_LIMIT // 1024} KiB "
                  f"disassembly limit; {len(beyond)} more samples "
                  f"({100 * len(beyond) / len(ips):.1f} % of JIT samples) fall in its code "
                  f"past that, up to {max(beyond) - base:#x} bytes from its start "
                  f"(the windows below cover the listed part only)")
    counts = collections.Counter(ip - base for ip in ips)
    print(f"\nhottest windows of {a.window} instructions in kernel {k} "
          f"(index of the first instruction, its offset, share of the kernel's samples, opcodes):")
    windows = []
    for i in range(0, len(ins), a.window):
        part = ins[i:i + a.window]
        windows.append((sum(counts[o] for o, _ in part), i, part))
    for s, i, part in sorted(windows, key=lambda t: -t[0])[: a.top]:
        ops = collections.Counter(t.split()[0] for _, t in part)
        summary = " ".join(f"{op}:{n}" for op, n in ops.most_common(8))
        print(f"{i:7d} {part[0][0]:#8x} {100 * s / hits:5.1f} %  {summary}")
    if a.annotate:
        with open(a.annotate, "w") as f:
            for i, (o, t) in enumerate(ins):
                f.write(f"{i:7d} {o:8x} {100 * counts[o] / hits:6.2f}  {t}\n")
        print(f"\nannotated listing: {a.annotate}")


if __name__ == "__main__":
    main()
