#!/usr/bin/env python3
"""Peer check of lanterna against Mitsuba 3 on a scene exported by
`lanterna scene export-mitsuba`.

Given the export directory and lanterna renders of the same scene (several EXRs of
disjoint sample ranges or different seeds, or `--lanterna BIN` to have this script
render them), it renders the exported scene with Mitsuba's `path` integrator several
times with different seeds, writes Mitsuba's EXR, and reports as JSON:

* the relative difference of the mean radiance per channel, with its standard error;
* per-block and per-pixel agreement: Welch's t-test of lanterna's batch means against
  Mitsuba's run means (variance estimated from the spread of the independent renders
  on each side), family-wise significance by Šidák's correction, plus the fraction of
  tests below 1 % against its binomial expectation;
* samples per second of each renderer (lanterna's from its EXR metadata, Mitsuba's
  timed here, excluding scene loading and the first, JIT-compiling run);
* MAE at equal time (and equal spp) against an independent higher-spp Mitsuba reference.

An export made with `--hide-emitters` stands for lanterna's `--hide-emitters` (emission
seen directly left out, the light the emitters' surfaces reflect kept): each Mitsuba image
is then max_depth D minus max_depth 1 with the same seed, and `--lanterna` renders with
`--hide-emitters`. (Mitsuba's own `hide_emitters` makes emitters invisible to camera rays.)

`agree` is true when none of the three families (image mean per channel, blocks, pixels)
rejects at family-wise significance `--alpha`. The per-pixel test assumes batch means
are roughly normal: with very skewed pixel estimates (e.g. direction sampling alone of
small lights at a few spp per batch) it becomes anti-conservative; give such cases more
spp per batch. The report's `schema` number changes only when keys change meaning.

The CLI and the JSON keys are meant to stay stable so that `lanterna bench` can call it.
Exit status: 0 when the check ran (whatever it found), 2 on bad input, and 1 with
`--fail-on-disagree` when the renders disagree.
"""

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

LLVM_PATHS = [
    "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1",
    "/usr/lib/x86_64-linux-gnu/libLLVM-19.so",
    "/usr/lib/x86_64-linux-gnu/libLLVM-17.so",
    "/usr/lib/x86_64-linux-gnu/libLLVM-15.so",
]


class InputError(Exception):
    pass


# ---------------------------------------------------------------------------------------
# Statistics (no SciPy): Student's t tail through the regularised incomplete beta.


def _betacf(a, b, x, iters=300):
    """Continued fraction of the incomplete beta (modified Lentz), elementwise."""
    tiny = 1e-300
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c = np.ones_like(x)
    d = 1.0 - qab * x / qap
    d = np.where(np.abs(d) < tiny, tiny, d)
    d = 1.0 / d
    h = d.copy()
    for m in range(1, iters + 1):
        m2 = 2 * m
        aa = m * (b - m) * x / ((qam + m2) * (a + m2))
        d = 1.0 + aa * d
        d = np.where(np.abs(d) < tiny, tiny, d)
        c = 1.0 + aa / c
        c = np.where(np.abs(c) < tiny, tiny, c)
        d = 1.0 / d
        h *= d * c
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))
        d = 1.0 + aa * d
        d = np.where(np.abs(d) < tiny, tiny, d)
        c = 1.0 + aa / c
        c = np.where(np.abs(c) < tiny, tiny, c)
        d = 1.0 / d
        delta = d * c
        h *= delta
        if np.all(np.abs(delta - 1.0) < 1e-12):
            break
    return h


def betainc(a, b, x):
    """Regularised incomplete beta I_x(a, b), elementwise over arrays."""
    a, b, x = np.broadcast_arrays(
        np.asarray(a, float), np.asarray(b, float), np.clip(np.asarray(x, float), 0, 1)
    )
    lgam = np.vectorize(math.lgamma)
    with np.errstate(divide="ignore", invalid="ignore"):
        front = np.exp(
            lgam(a + b) - lgam(a) - lgam(b) + a * np.log(np.maximum(x, 1e-300))
            + b * np.log(np.maximum(1 - x, 1e-300))
        )
        direct = x < (a + 1) / (a + b + 2)
        r1 = front * _betacf(a, b, x) / a
        r2 = 1.0 - front * _betacf(b, a, 1 - x) / b
    out = np.where(direct, r1, r2)
    out = np.where(x <= 0, 0.0, np.where(x >= 1, 1.0, out))
    return np.clip(out, 0.0, 1.0)


def t_two_sided_p(t, df):
    """Two-sided p-value of Student's t with df degrees of freedom."""
    t = np.asarray(t, float)
    df = np.asarray(df, float)
    return betainc(df / 2.0, 0.5, df / (df + t * t))


def welch(xs, ys):
    """Welch's t-test between two sets of independent estimates, along axis 0.

    Returns (mean_x, mean_y, standard error of the difference, t, p). Where the
    difference's standard error is within the renderers' storage resolution (both sides
    constant, or a pixel so dim that its samples' spread is below it), p is 1 if the means
    are equal to that resolution, and otherwise that of a normal test of the difference
    against the standard error and the resolution together.
    """
    nx, ny = xs.shape[0], ys.shape[0]
    mx, my = xs.mean(0), ys.mean(0)
    vx = xs.var(0, ddof=1) / nx
    vy = ys.var(0, ddof=1) / ny
    se2 = vx + vy
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (mx - my) / np.sqrt(se2)
        df = se2 * se2 / (vx * vx / (nx - 1) + vy * vy / (ny - 1))
    df = np.where(np.isfinite(df) & (df > 0), df, 1.0)
    p = t_two_sided_p(np.where(np.isfinite(t), t, 0.0), df)
    # Both sides constant (a pixel that sees only an emitter, say): equal unless they
    # differ by more than the two renderers' storage can explain. Mitsuba sums its
    # samples in float32, which for a constant pixel of 1,024 samples drifts by ~1e-5
    # relative (seen: 7.111566 against 7.111465), and lanterna keeps decoded colour
    # textures as half floats, within 2.5e-4 of Mitsuba's float32 texels (an emissive
    # sign's pixel, seen: 0.0182152 against 0.0182115). lanterna's film rounds each
    # sample stochastically to units of 2^-20, so its batches of a constant pixel
    # spread by a fraction of that unit: a standard error below one unit plus
    # Mitsuba's drift is storage, not sampling, and such pixels count as constant. A pixel
    # whose standard error is below that resolution need not be constant, though: one
    # lit at 1e-5 of a 0.1 image (random_scene.py --materials, seed 110, light reuse)
    # had lanterna 1.140e-5 against Mitsuba 1.043e-5 with a standard error of 4.5e-7,
    # a difference of one film unit, and was rejected with p = 0. So where the means
    # are not equal to the resolution, the difference is tested against the standard
    # error and the resolution together: a difference of a few units passes, a constant
    # pixel 1 % off does not.
    unit = 2.0 ** -20
    resolution = unit + 1e-5 * np.maximum(np.abs(mx), np.abs(my))
    degenerate = se2 <= resolution * resolution
    with np.errstate(divide="ignore", invalid="ignore"):
        z = (mx - my) / np.sqrt(se2 + resolution * resolution)
    p_floor = t_two_sided_p(np.where(np.isfinite(z), z, 0.0), np.full_like(z, 1e6))
    p = np.where(
        degenerate, np.where(np.isclose(mx, my, rtol=1e-3, atol=unit), 1.0, p_floor), p
    )
    return mx, my, np.sqrt(se2), t, p


def finite_json(v):
    """`v` with every non-finite float replaced by None, for strict JSON."""
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, dict):
        return {k: finite_json(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [finite_json(x) for x in v]
    return v


def binomial_tail(k, n, q):
    """P[X >= k] for X ~ Binomial(n, q)."""
    if k <= 0:
        return 1.0
    logs = [
        math.lgamma(n + 1) - math.lgamma(i + 1) - math.lgamma(n - i + 1)
        + i * math.log(q) + (n - i) * math.log1p(-q)
        for i in range(k, n + 1)
    ]
    m = max(logs)
    return float(min(1.0, math.exp(m) * sum(math.exp(v - m) for v in logs)))


def blocks(img, size):
    """Mean over size×size blocks of an (..., H, W, C) array (ragged edges allowed)."""
    h, w = img.shape[-3], img.shape[-2]
    by, bx = -(-h // size), -(-w // size)
    out = np.zeros(img.shape[:-3] + (by, bx, img.shape[-1]))
    for j in range(by):
        for i in range(bx):
            out[..., j, i, :] = img[..., j * size:(j + 1) * size, i * size:(i + 1) * size, :].mean(
                axis=(-3, -2)
            )
    return out


# Block and pixel means below this share of the image's mean radiance, on both sides, are
# not tested: no film or display resolves them. The index-matched `dielectric` (index
# 1.00001) that stands for glass without Fresnel reflection reflects 1e-10-1e-8 of the
# light in Mitsuba, where lanterna's pane reflects nothing; pixels lit only that way
# (random_scene.py --materials, seed 11: 1e-8 against an image mean of 0.08, with no
# variance on lanterna's side) failed the pixel test with p = 3e-15.
NEGLIGIBLE_SHARE = 1e-6


def agreement(lt, mi_, size, alpha):
    """Per-block (size > 1) or per-pixel (size = 1) Welch tests between the stacks."""
    a = blocks(lt, size) if size > 1 else lt
    b = blocks(mi_, size) if size > 1 else mi_
    mx, my, se, t, p = welch(a.astype(np.float64), b.astype(np.float64))
    floor = NEGLIGIBLE_SHARE * max(abs(float(lt.mean())), abs(float(mi_.mean())))
    negligible = (np.abs(mx) <= floor) & (np.abs(my) <= floor)
    informative = ~(((a == 0).all(0) & (b == 0).all(0)) | negligible)
    n = int(informative.sum())
    res = {"size": size, "tests": n, "alpha": alpha}
    if n == 0:
        res.update(agree=True, min_p=1.0)
        return res
    pv = np.where(informative, p, 1.0)
    threshold = 1.0 - (1.0 - alpha) ** (1.0 / n)
    worst = np.unravel_index(np.argmin(pv), pv.shape)
    below = {}
    for q in (0.01, 0.05):
        k = int(((pv < q) & informative).sum())
        below[str(q)] = {
            "count": k,
            "expected": q * n,
            "binomial_p": binomial_tail(k, n, q),
        }
    res.update(
        sidak_threshold=threshold,
        min_p=float(pv[worst]),
        agree=bool(pv[worst] >= threshold),
        worst={
            "x": int(worst[1] * size),
            "y": int(worst[0] * size),
            "channel": "RGB"[worst[2]],
            "lanterna": float(mx[worst]),
            "mitsuba": float(my[worst]),
            "stderr": float(se[worst]),
            "t": float(t[worst]),
        },
        below=below,
    )
    return res


# ---------------------------------------------------------------------------------------
# Images.


def read_lanterna_exr(mi, path):
    try:
        bmp = mi.Bitmap(path)
    except Exception as e:  # noqa: BLE001 - Mitsuba raises RuntimeError subclasses
        raise InputError(f"{path}: cannot read the EXR: {e}")
    names = [f.name for f in bmp.struct_()]
    try:
        idx = [names.index(c) for c in ("R", "G", "B")]
    except ValueError:
        raise InputError(f"{path}: no R, G, B channels (has {', '.join(names)})")
    arr = np.array(bmp)[..., idx].astype(np.float64)
    meta = bmp.metadata()
    keys = set(meta.keys())

    def get(k, conv=str):
        return conv(meta[k]) if k in keys else None

    info = {
        "path": path,
        "spp": get("lanterna.spp", int),
        "sample_offset": get("lanterna.sample_offset", int) or 0,
        "seed": get("lanterna.seed", int) or 0,
        "method": get("lanterna.method"),
        "max_depth": get("lanterna.max_depth", int),
        "render_seconds": get("lanterna.render_seconds", float),
        "scene_hash": get("lanterna.scene_hash"),
    }
    return arr, info


def write_exr(mi, path, img):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    tmp = path + ".tmp.exr"
    mi.Bitmap(np.ascontiguousarray(img.astype(np.float32))).write(tmp)
    os.replace(tmp, path)


def mae(img, ref):
    return float(np.abs(img - ref).mean())


# ---------------------------------------------------------------------------------------


def pick_variant(mi, wanted):
    if wanted:
        return wanted
    if "llvm_ad_rgb" in mi.variants() and os.environ.get("DRJIT_LIBLLVM_PATH"):
        return "llvm_ad_rgb"
    return "scalar_rgb"


def render_lanterna_batches(args, manifest, out_dir):
    """Render `--batches` disjoint sample ranges with the lanterna binary."""
    paths = []
    for k in range(args.batches):
        path = os.path.join(out_dir, f"lanterna_{args.method}_{k}.exr")
        cmd = [
            args.lanterna, "--log", "warn", "render", manifest["scene_path"],
            "--width", str(manifest["width"]), "--height", str(manifest["height"]),
            "--max-depth", str(manifest["max_depth"]), "--method", args.method,
            "--spp", str(args.spp), "--sample-offset", str(k * args.spp),
            "--seed", str(args.seed), "-o", path, "--no-png", "--quiet",
        ]
        if manifest.get("camera_index") is not None:
            cmd += ["--camera", str(manifest["camera_index"])]
        # The version of the file the export shows: its animation pose and variant.
        for key, flag in (("animation_time", "--animation-time"), ("animation", "--animation"),
                          ("variant", "--variant")):
            if manifest.get(key) is not None and not any(
                    a == flag or a.startswith(flag + "=") for a in args.lanterna_arg):
                cmd += [flag, str(manifest[key])]
        cmd += args.lanterna_arg
        if manifest.get("hide_emitters") and "--hide-emitters" not in cmd:
            cmd.append("--hide-emitters")
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise InputError(f"lanterna failed ({' '.join(cmd)}):\n{r.stderr.strip()}")
        paths.append(path)
    return paths


def check_independent(infos):
    """Batches must come from disjoint sample ranges or different seeds."""
    for i in range(len(infos)):
        for j in range(i + 1, len(infos)):
            a, b = infos[i], infos[j]
            if a["seed"] != b["seed"] or a["spp"] is None or b["spp"] is None:
                continue
            lo = max(a["sample_offset"], b["sample_offset"])
            hi = min(a["sample_offset"] + a["spp"], b["sample_offset"] + b["spp"])
            if lo < hi:
                raise InputError(
                    f"{a['path']} and {b['path']} share samples [{lo}, {hi}) with seed "
                    f"{a['seed']}: they are not independent (use disjoint --sample-offset "
                    "ranges or different seeds)"
                )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("export_dir", help="directory written by `lanterna scene export-mitsuba`")
    ap.add_argument("lanterna_exr", nargs="*",
                    help="lanterna renders of the scene: independent batches (disjoint "
                         "--sample-offset ranges or different seeds), at least 2")
    ap.add_argument("--lanterna", metavar="BIN",
                    help="render the lanterna batches with this binary instead")
    ap.add_argument("--method", default="pt", help="lanterna method with --lanterna")
    ap.add_argument("--batches", type=int, default=8, help="lanterna batches with --lanterna")
    ap.add_argument("--spp", type=int, help="spp per lanterna batch (with --lanterna) and "
                    "per Mitsuba run (default: the lanterna batches' spp)")
    ap.add_argument("--seed", type=int, default=0, help="lanterna seed with --lanterna")
    ap.add_argument("--lanterna-arg", action="append", default=[],
                    help="extra argument for `lanterna render` (repeatable)")
    ap.add_argument("--runs", type=int, default=8, help="independent Mitsuba renders")
    ap.add_argument("--mitsuba-spp", type=int, help="spp per Mitsuba run (default: --spp)")
    ap.add_argument("--variant", help="Mitsuba variant (default llvm_ad_rgb if "
                    "DRJIT_LIBLLVM_PATH is set or libLLVM is found, else scalar_rgb)")
    ap.add_argument("--block", type=int, default=8, help="block size of the block test")
    ap.add_argument("--alpha", type=float, default=1e-3,
                    help="family-wise significance of the block and pixel tests")
    ap.add_argument("--reference-spp", type=int, default=0,
                    help="spp of the independent Mitsuba reference for MAE (0: skip MAE)")
    ap.add_argument("-o", "--output", help="Mitsuba's mean EXR (default: "
                    "<export_dir>/mitsuba.exr)")
    ap.add_argument("--json", help="write the report here (default: stdout)")
    ap.add_argument("--t-exr", metavar="PATH",
                    help="also write per-pixel Welch t statistics (lanterna − Mitsuba) as an EXR")
    ap.add_argument("--keep-lanterna", metavar="DIR",
                    help="with --lanterna: keep its batch EXRs (and their mean) in DIR")
    ap.add_argument("--gltf-bsdf", action="store_true",
                    help="render every material with the glTF BRDF plugins of "
                    "scripts/mitsuba_gltf_bsdf.py and mitsuba_gltf_layers.py (exact for "
                    "untextured opaque metallic-roughness materials, with clearcoat, "
                    "sheen, thin-walled transmission or diffuse transmission factors) "
                    "instead of the export's BSDFs")
    ap.add_argument("--fail-on-disagree", action="store_true",
                    help="exit with status 1 when the block test rejects agreement")
    args = ap.parse_args(argv)

    if not os.environ.get("DRJIT_LIBLLVM_PATH"):
        for p in LLVM_PATHS:
            if os.path.exists(p):
                os.environ["DRJIT_LIBLLVM_PATH"] = p
                break
    try:
        import mitsuba as mi
    except ImportError as e:
        raise InputError(f"cannot import mitsuba ({e}); install it with `pip install mitsuba`")

    variant = pick_variant(mi, args.variant)
    try:
        mi.set_variant(variant)
    except Exception:  # noqa: BLE001
        variant = "scalar_rgb"
        mi.set_variant(variant)

    manifest_path = os.path.join(args.export_dir, "lanterna_export.json")
    xml = os.path.join(args.export_dir, "scene.xml")
    if not os.path.isfile(manifest_path) or not os.path.isfile(xml):
        raise InputError(f"{args.export_dir}: not a lanterna Mitsuba export "
                         "(no lanterna_export.json / scene.xml)")
    with open(manifest_path) as f:
        manifest = json.load(f)

    tmpdir = tempfile.mkdtemp(prefix="mitsuba_compare_")
    try:
        paths = args.lanterna_exr
        if args.lanterna:
            if not args.spp:
                raise InputError("--lanterna needs --spp")
            paths = render_lanterna_batches(args, manifest, tmpdir)
        if len(paths) < 2:
            raise InputError("need at least two independent lanterna renders (or --lanterna)")
        imgs, infos = [], []
        for p in paths:
            img, info = read_lanterna_exr(mi, p)
            if img.shape[:2] != (manifest["height"], manifest["width"]):
                raise InputError(f"{p}: {img.shape[1]}×{img.shape[0]} but the export is "
                                 f"{manifest['width']}×{manifest['height']}")
            if info["scene_hash"] and info["scene_hash"] != manifest["scene_hash"]:
                raise InputError(f"{p}: rendered from scene {info['scene_hash']} but the "
                                 f"export is of {manifest['scene_hash']}")
            if info["max_depth"] is not None and info["max_depth"] != manifest["max_depth"]:
                raise InputError(f"{p}: max depth {info['max_depth']} but the export has "
                                 f"{manifest['max_depth']}")
            imgs.append(img)
            infos.append(info)
        check_independent(infos)
        lt = np.stack(imgs)
        lt_spp = infos[0]["spp"] or args.spp or 16
        m_spp = args.mitsuba_spp or args.spp or lt_spp

        if args.gltf_bsdf:
            sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
            import mitsuba_gltf_bsdf
            import mitsuba_gltf_layers
            mitsuba_gltf_layers.register()
            try:
                xml = mitsuba_gltf_bsdf.rewrite_export(args.export_dir)
            except ValueError as e:
                raise InputError(f"--gltf-bsdf: {e}")
        approximations = manifest.get("approximations", [])
        if args.gltf_bsdf:
            # The plugins are the glTF model itself: what the export approximated by
            # `principled` (coats and sheens included) or by a smooth `thindielectric` is
            # now exact (materials they cannot write were refused above).
            exact_now = ("glTF metallic-roughness", "its clearcoat", "its sheen",
                         "KHR_materials_transmission (roughness", "its anisotropy (strength",
                         "its diffuse transmission (factor", "its iridescence (factor")
            approximations = [a for a in approximations
                              if not any(e in a for e in exact_now)]
        scene = mi.load_file(xml, max_depth=manifest["max_depth"])
        # lanterna's --hide-emitters leaves out emission seen directly and keeps the light
        # the emitters' surfaces reflect; Mitsuba's hide_emitters would make them
        # invisible to camera rays instead. Max depth D minus max depth 1 with the same
        # seed is lanterna's quantity: the camera rays of both renders are the same.
        direct_view = (mi.load_file(xml, max_depth=1)
                       if manifest.get("hide_emitters") else None)

        def render(spp, seed):
            img = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)
            if direct_view is not None:
                img -= np.array(mi.render(direct_view, spp=spp, seed=seed), dtype=np.float64)
            return img

        pixels = manifest["width"] * manifest["height"]
        # Warm-up (JIT compilation in the LLVM variant), then timed independent runs with
        # seeds far from those of the reference and the equal-time render.
        t0 = time.perf_counter()
        render(m_spp, 10_000_000)
        warmup = time.perf_counter() - t0
        runs, times = [], []
        for k in range(args.runs):
            t0 = time.perf_counter()
            img = render(m_spp, k)
            times.append(time.perf_counter() - t0)
            runs.append(img)
        ms = np.stack(runs)
        m_rate = m_spp * pixels / float(np.median(times))
        out_exr = args.output or os.path.join(args.export_dir, "mitsuba.exr")
        write_exr(mi, out_exr, ms.mean(0))

        # Image means per channel, with standard errors from the spread of the renders.
        lm, mm = lt.mean(axis=(1, 2)), ms.mean(axis=(1, 2))
        mx, my, se, t, p = welch(lm, mm)
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.where(my != 0, mx / my - 1.0, 0.0)
            rel_se = np.where(my != 0, se / np.abs(my), 0.0)
        mean_report = {
            "lanterna": mx.tolist(),
            "mitsuba": my.tolist(),
            "rel_diff": rel.tolist(),
            "rel_diff_stderr": rel_se.tolist(),
            "t": [float(v) if np.isfinite(v) else 0.0 for v in t],
            "p": p.tolist(),
        }
        if args.t_exr:
            _, _, _, tpix, _ = welch(lt, ms)
            write_exr(mi, args.t_exr, np.nan_to_num(tpix))
        if args.keep_lanterna:
            os.makedirs(args.keep_lanterna, exist_ok=True)
            for pth in paths:
                shutil.copy(pth, args.keep_lanterna)
            write_exr(mi, os.path.join(args.keep_lanterna, "lanterna_mean.exr"), lt.mean(0))
        block = agreement(lt, ms, args.block, args.alpha)
        pixel = agreement(lt, ms, 1, args.alpha)
        mean_ok = bool(p.min() >= 1.0 - (1.0 - args.alpha) ** (1.0 / 3.0))

        secs = [i["render_seconds"] for i in infos if i["render_seconds"]]
        l_rate = (sum(i["spp"] for i in infos if i["render_seconds"]) * pixels / sum(secs)
                  if secs else None)
        report = {
            "schema": 1,
            "export_dir": os.path.abspath(args.export_dir),
            "scene": manifest.get("scene_path"),
            "scene_hash": manifest.get("scene_hash"),
            "exact": manifest.get("exact") or (args.gltf_bsdf and not approximations),
            "approximations": approximations,
            "width": manifest["width"],
            "height": manifest["height"],
            "max_depth": manifest["max_depth"],
            "hide_emitters": bool(manifest.get("hide_emitters")),
            "lanterna": {
                "method": infos[0]["method"],
                "batches": len(infos),
                "spp_per_batch": lt_spp,
                "files": [os.path.abspath(i["path"]) for i in infos] if not args.lanterna else [],
            },
            "mitsuba": {
                "variant": variant,
                "version": mi.__version__,
                "runs": args.runs,
                "spp_per_run": m_spp,
                "exr": os.path.abspath(out_exr),
            },
            "mean": mean_report,
            "blocks": block,
            "pixels": pixel,
            "agree": bool(block["agree"] and pixel["agree"] and mean_ok),
            "performance": {
                "lanterna_samples_per_s": l_rate,
                "mitsuba_samples_per_s": m_rate,
                "mitsuba_warmup_seconds": warmup,
                "mitsuba_run_seconds": times,
            },
        }

        if args.reference_spp > 0:
            ref = render(args.reference_spp, 20_000_000)
            write_exr(mi, os.path.splitext(out_exr)[0] + "_reference.exr", ref)
            same = ms[0] if m_spp == lt_spp else render(lt_spp, 40_000_000)
            eq = {"reference_spp": args.reference_spp,
                  "equal_spp": {"spp": lt_spp, "lanterna": mae(lt[0], ref),
                                "mitsuba": mae(same, ref)}}
            if infos[0]["render_seconds"]:
                t_l = infos[0]["render_seconds"]
                # Mitsuba's speed grows with the spp of one call (per-call costs), so
                # the rate of the comparison runs can give it well under lanterna's
                # time (seen: 0.63 s of 0.88 s). Re-render with the spp scaled by the
                # time taken until it is within 5 % of lanterna's (6 tries at most).
                # The render whose time came closest counts: at budgets of a tenth of
                # a second one call's time can jump (seen: 0.05 s for the third try
                # of a 0.13-s budget), and the last try is not the best one.
                spp_eq = max(1, int(round(m_rate * t_l / pixels)))
                best = None
                for attempt in range(6):
                    t0 = time.perf_counter()
                    img = render(spp_eq, 30_000_000 + attempt)
                    t_m = time.perf_counter() - t0
                    off = abs(t_m / t_l - 1.0)
                    if best is None or off < best[0]:
                        best = (off, spp_eq, t_m, img)
                    if off <= 0.05:
                        break
                    spp_eq = max(1, int(round(spp_eq * t_l / t_m)))
                _, spp_eq, t_m, img = best
                eq["equal_time"] = {
                    "seconds": t_l,
                    "lanterna": {"spp": lt_spp, "mae": mae(lt[0], ref)},
                    "mitsuba": {"spp": spp_eq, "seconds": t_m, "mae": mae(img, ref)},
                }
            report["mae"] = eq

        # Strict JSON (no NaN or Infinity, which serde_json and others refuse).
        text = json.dumps(finite_json(report), indent=2, allow_nan=False)
        if args.json:
            tmp = args.json + ".tmp"
            with open(tmp, "w") as f:
                f.write(text + "\n")
            os.replace(tmp, args.json)
        else:
            print(text)
        if args.fail_on_disagree and not report["agree"]:
            return 1
        return 0
    finally:
        shutil.rmtree(tmpdir, ignore_errors=True)


if __name__ == "__main__":
    try:
        sys.exit(main())
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(2)
