import sys, numpy as np, mitsuba as mi
mi.set_variant("scalar_rgb")
ex=np.load("exact.npy")
def load(p): return np.array(mi.Bitmap(p)).astype(np.float64)[...,:3].mean(-1)
for tag in sys.argv[1:]:
    import glob
    fs=sorted(glob.glob(tag+"_*.exr"))
    imgs=np.stack([load(f) for f in fs])
    e=imgs-ex
    mse=(e**2).mean()
    rel=np.abs(e)/(ex+1e-3)
    # per-pixel second moment relative
    print(f"{tag}: n={len(fs)} MAE {np.abs(e).mean():.5f} relMSE {(e**2/(ex**2+1e-3)).mean():.5f} RMSE {np.sqrt(mse):.5f} max-rel {rel.max():.2f} p99.9-rel {np.quantile(rel,0.999):.3f}")
