"""The paper's Fig. 6: MAE against samples per pixel for pt, ris, guided and guided-ris,
on a log-log plot. A high-spp `pt` render of disjoint samples is the reference.

    pip install . matplotlib
    python examples/fig6_mae_vs_spp.py [scene.gltf] [--width 160] [--ref-spp 4096] [-o fig6.png]

On lavapipe (2 cores) the street at 160×90 takes about half an hour, mostly for the
reference; `--ref-spp 1024 --max-spp 64` gives a rough figure in a few minutes.
"""

import argparse

import matplotlib.pyplot as plt

import lanterna

p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
p.add_argument("scene", nargs="?", default="scenes/street.gltf")
p.add_argument("--width", type=int, default=160)
p.add_argument("--ref-spp", type=int, default=4096)
p.add_argument("--max-spp", type=int, default=256)
p.add_argument("-o", "--output", default="fig6_mae_vs_spp.png")
args = p.parse_args()

scene = lanterna.load_scene(args.scene)
budgets = [1 << k for k in range(args.max_spp.bit_length()) if 1 << k <= args.max_spp]
# Sample indices from 2^30 on: the reference is independent of every compared render.
reference = lanterna.Renderer(scene, args.width, method="pt").render(
    spp=args.ref_spp, sample_offset=1 << 30
)

fig, ax = plt.subplots(figsize=(5, 4))
for method in lanterna.METHODS:
    r = lanterna.Renderer(scene, args.width, method=method)  # one setup per method
    errors = [lanterna.mae(r.render(spp=n, progress=False), reference) for n in budgets]
    print(method, " ".join(f"{e:.4f}" for e in errors))
    ax.loglog(budgets, errors, "o-", label=method)
ax.set(xlabel="samples per pixel", ylabel="MAE", title=f"{scene.path} ({args.width} px wide)")
ax.legend()
fig.tight_layout()
fig.savefig(args.output, dpi=150)
print("wrote", args.output)
