import json, struct, math, sys
# floor 8x8, 4 tilted flat-hemisphere IES lamps, 2 hard wide spots, 16 point lights
ies = """IESNA:LM-63-2002
[TEST] exp
TILT=NONE
1 -1 1 5 1 1 2 0.1 0.1 0
1 1 20
0 22.5 45 67.5 90
0
1000 1000 1000 1000 1000
"""
open("flat.ies","w").write(ies)
bin=b""
c=[[-4,0,-4],[-4,0,4],[4,0,4],[4,0,-4]]
for i in [0,1,2,0,2,3]: bin+=struct.pack("<3f",*c[i])
for i in range(6): bin+=struct.pack("<3f",0,1,0)
open("floor.bin","wb").write(bin)
def quat_x(deg):
    a=math.radians(deg)/2; return [math.sin(a),0,0,math.cos(a)]
nodes=[{"mesh":0}]
ext_lights=[]
punct=[]
for i,(x,z) in enumerate([(-2,-2),(2,-2),(-2,2),(2,2)]):
    # IES aims down (-Z local is node -Z? EXT_lights_ies: aim is local -Z? rotate -90 about x to point down, then tilt)
    nodes.append({"translation":[x,0.6,z],"rotation":quat_x(-90+65),"extensions":{"EXT_lights_ies":{"light":0,"multiplier":0.003}}})
for i,(x,z) in enumerate([(0,-3),(0,3)]):
    punct.append({"type":"spot","color":[1,1,1],"intensity":30,"spot":{"innerConeAngle":1.35,"outerConeAngle":1.3963}})
    nodes.append({"translation":[x,0.5,z],"rotation":quat_x(-90+60),"extensions":{"KHR_lights_punctual":{"light":i}}})
import random
r=random.Random(3)
for k in range(16):
    punct.append({"type":"point","color":[1,1,1],"intensity":2})
    nodes.append({"translation":[r.uniform(-4,4),r.uniform(1.0,2.5),r.uniform(-4,4)],"extensions":{"KHR_lights_punctual":{"light":len(punct)-1}}})
nodes.append({"camera":0,"translation":[0,10,0],"rotation":quat_x(-90)})
doc={"asset":{"version":"2.0"},"extensionsUsed":["EXT_lights_ies","KHR_lights_punctual","KHR_materials_specular"],
 "extensions":{"EXT_lights_ies":{"lights":[{"uri":"flat.ies"}]},"KHR_lights_punctual":{"lights":punct}},
 "scene":0,"scenes":[{"nodes":list(range(len(nodes)))}],"nodes":nodes,
 "cameras":[{"type":"orthographic","orthographic":{"xmag":4,"ymag":4,"znear":0.1,"zfar":100}}],
 "materials":[{"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.8,0.8,1],"metallicFactor":0,"roughnessFactor":1},"extensions":{"KHR_materials_specular":{"specularFactor":0}}}],
 "meshes":[{"primitives":[{"attributes":{"POSITION":0,"NORMAL":1},"material":0}]}],
 "buffers":[{"uri":"floor.bin","byteLength":len(bin)}],
 "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":72},{"buffer":0,"byteOffset":72,"byteLength":72}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":6,"type":"VEC3","min":[-4,0,-4],"max":[4,0,4]},{"bufferView":1,"componentType":5126,"count":6,"type":"VEC3"}]}
json.dump(doc,open("exp.gltf","w"),indent=1)
