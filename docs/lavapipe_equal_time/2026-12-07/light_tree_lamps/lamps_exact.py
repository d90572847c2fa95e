import json, numpy as np, math, mitsuba as mi
mi.set_variant("scalar_rgb")
doc=json.load(open("exp.gltf"))
N=128; S=6
g=(np.arange(N*S)+0.5)/(N*S)*8-4
X,Z=np.meshgrid(g,g)  # rows = z
P=np.stack([X,np.zeros_like(X),Z],-1)
def rotq(q,v):
    x,y,z,w=q; u=np.array([x,y,z]); 
    return 2*np.dot(u,v)*u+(w*w-np.dot(u,u))*v+2*w*np.cross(u,v)
L=np.zeros(X.shape)
punct=doc["extensions"]["KHR_lights_punctual"]["lights"]
for n in doc["nodes"]:
    e=n.get("extensions",{})
    if not e: continue
    t=np.array(n["translation"],float); q=n.get("rotation",[0,0,0,1])
    d=P-t; r2=(d**2).sum(-1); w=d/np.sqrt(r2)[...,None]
    cos_r=np.clip(-w[...,1],0,None)
    if "EXT_lights_ies" in e:
        aim=rotq(q,np.array([0,0,-1.0])); c=w@aim
        I=np.where(c>=0,1000*e["EXT_lights_ies"]["multiplier"],0)
    else:
        l=punct[e["KHR_lights_punctual"]["light"]]
        I=np.full(X.shape,l["intensity"],float)
        if l["type"]=="spot":
            aim=rotq(q,np.array([0,0,-1.0])); c=w@aim
            co=math.cos(l["spot"]["outerConeAngle"]); ci=math.cos(l["spot"]["innerConeAngle"])
            tt=np.clip((c-co)/(ci-co),0,1); I=I*tt*tt
    L+=I*cos_r/r2
L*=0.8/math.pi
img=L.reshape(N,S,N,S).mean(axis=(1,3))
np.save("exact.npy",img)
ref=np.array(mi.Bitmap("ref.exr")).astype(float)[...,:3].mean(-1)
print("exact mean",img.mean(),"ref mean",ref.mean(),"ratio",ref.mean()/img.mean())
print("rel diff of blocks", np.abs((ref.reshape(8,16,8,16).mean(axis=(1,3))/img.reshape(8,16,8,16).mean(axis=(1,3)))-1).max())
