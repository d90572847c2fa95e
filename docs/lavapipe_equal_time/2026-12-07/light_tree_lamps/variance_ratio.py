import sys, glob, numpy as np, mitsuba as mi
mi.set_variant("scalar_rgb")
def load(p): return np.array(mi.Bitmap(p)).astype(np.float64)[...,:3].mean(-1)
name=sys.argv[1]; res={}
for tag in ("old","new"):
    fs=sorted(glob.glob(f"{name}_{tag}_*.exr")); imgs=np.stack([load(f) for f in fs])
    m=imgs.mean(0); v=imgs.var(0,ddof=1)
    res[tag]=(v.mean(), (v/(m**2+1e-2)).mean(), m.mean(), len(fs))
o,n=res["old"],res["new"]
print(f"{sys.argv[2]},{o[3]},{o[2]:.5f},{n[2]:.5f},{o[0]:.4e},{n[0]:.4e},{n[0]/o[0]:.3f},{n[1]/o[1]:.3f}")
