"""Read a .glb by hand as energywave's loader does and compare it with export_gltf.py's JSON.

    python3 check_glb.py OUT.glb OUT.json        (needs numpy: Debian python3-numpy)

The reading follows src/objects/mesh.rs `MeshData::load`: the default scene's node trees, each node's
world matrix parent * local (TRS or matrix), positions through it, normals through its inverse transpose
(normalised, as src/objects/tessellate.rs does), one baseColorFactor per primitive. It prints the file's
nodes, materials and primitives' attributes, then for each mesh the largest differences from Blender's
own world-space triangles, normals and bounding box (glTF axes), and whether each triangle's corner
normals are all equal (flat) or not (smooth). A reference for the Rust test, not a test itself.
"""
import json, struct, sys
import numpy as np
glb, js = sys.argv[1], sys.argv[2]
data = open(glb, "rb").read()
magic, version, length = struct.unpack_from("<4sII", data, 0)
assert magic == b"glTF" and version == 2 and length == len(data)
off = 12; chunks = {}
while off < len(data):
    n, kind = struct.unpack_from("<I4s", data, off); chunks[kind] = data[off + 8: off + 8 + n]; off += 8 + n
doc = json.loads(chunks[b"JSON"]); binc = chunks[b"BIN\x00"]
print("asset", doc["asset"]); print("extensionsUsed", doc.get("extensionsUsed"), "required", doc.get("extensionsRequired"))
print("scene", doc.get("scene"), "scenes", doc["scenes"])
for i, n in enumerate(doc["nodes"]):
    print(f"node {i}", {k: v for k, v in n.items()})
for m in doc["materials"]:
    print("material", m["name"], m.get("pbrMetallicRoughness"), m.get("doubleSided"))
for m in doc["meshes"]:
    for p in m["primitives"]:
        print("mesh", m["name"], "mode", p.get("mode", 4), "attributes", sorted(p["attributes"]), "material", p.get("material"))
COMP = {5126: ("f", 4), 5125: ("I", 4), 5123: ("H", 2), 5121: ("B", 1)}
NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
def accessor(i):
    a = doc["accessors"][i]; bv = doc["bufferViews"][a["bufferView"]]
    fmt, size = COMP[a["componentType"]]; nc = NCOMP[a["type"]]
    stride = bv.get("byteStride", size * nc); start = bv.get("byteOffset", 0) + a.get("byteOffset", 0)
    out = [struct.unpack_from("<" + fmt * nc, binc, start + k * stride) for k in range(a["count"])]
    return np.array(out, dtype=np.float64)
def local(n):
    if "matrix" in n: return np.array(n["matrix"], dtype=np.float64).reshape(4, 4).T
    t = n.get("translation", [0, 0, 0]); x, y, z, w = n.get("rotation", [0, 0, 0, 1]); s = n.get("scale", [1, 1, 1])
    R = np.array([[1-2*(y*y+z*z), 2*(x*y-z*w), 2*(x*z+y*w)], [2*(x*y+z*w), 1-2*(x*x+z*z), 2*(y*z-x*w)], [2*(x*z-y*w), 2*(y*z+x*w), 1-2*(x*x+y*y)]])
    M = np.eye(4); M[:3, :3] = R * np.array(s); M[:3, 3] = t; return M
loaded = {}
stack = [(i, np.eye(4)) for i in doc["scenes"][doc.get("scene", 0)]["nodes"]]
while stack:
    i, parent = stack.pop(); n = doc["nodes"][i]; world = parent @ local(n)
    nw = np.linalg.inv(world[:3, :3]).T
    if "mesh" in n:
        tris, nors, cols = [], [], []
        for p in doc["meshes"][n["mesh"]]["primitives"]:
            pos = accessor(p["attributes"]["POSITION"]); pos = (world[:3, :3] @ pos.T).T + world[:3, 3]
            nor = (nw @ accessor(p["attributes"]["NORMAL"]).T).T
            nor /= np.linalg.norm(nor, axis=1, keepdims=True)
            idx = accessor(p["indices"]).astype(int).ravel()
            base = doc["materials"][p["material"]]["pbrMetallicRoughness"].get("baseColorFactor", [1, 1, 1, 1])
            for t in idx.reshape(-1, 3):
                tris.append(pos[t]); nors.append(nor[t]); cols.append(base)
        loaded[n["name"]] = (np.array(tris), np.array(nors), np.array(cols))
    stack.extend((c, world) for c in n.get("children", []))
ref = json.load(open(js))
def key(tri):  # a triangle as a sorted tuple of rounded corners (order-free)
    return tuple(sorted(tuple(np.round(c, 5)) for c in tri))
for o in ref["objects"]:
    if "mesh" not in o: continue
    m = o["mesh"]; tris, nors, cols = loaded[o["name"]]
    bt = np.array(m["triangles"]); bn = np.array(m["normals"])
    bbox = (tris.reshape(-1, 3).min(0), tris.reshape(-1, 3).max(0))
    # match triangles by their corners, then compare positions and normals corner by corner
    cent = tris.mean(axis=1); used = np.zeros(len(tris), bool)
    worst_p = worst_n = 0.0; unmatched = 0
    for t, tn in zip(bt, bn):
        d = np.linalg.norm(cent - t.mean(axis=0), axis=1); d[used] = np.inf; k = int(np.argmin(d))
        if d[k] > 1e-4: unmatched += 1; continue
        used[k] = True
        for c in range(3):
            j = int(np.argmin(np.linalg.norm(tris[k] - t[c], axis=1)))
            worst_p = max(worst_p, np.linalg.norm(tris[k][j] - t[c])); worst_n = max(worst_n, np.linalg.norm(nors[k][j] - tn[c]))
    print(f"{o['name']}: file {len(tris)} triangles, Blender {len(bt)}; unmatched {unmatched}; "
          f"max |position diff| {worst_p:.2e}, max |normal diff| {worst_n:.2e}; "
          f"bbox diff {max(np.abs(bbox[0]-m['bbox_min']).max(), np.abs(bbox[1]-m['bbox_max']).max()):.2e}; "
          f"baseColorFactor {cols[0].tolist()} vs Blender {m['base_color_linear']}")
    # flat: each triangle's three corner normals equal (and equal to the face normal); smooth: not
    same = np.all(np.abs(nors - nors[:, :1]).max(axis=(1, 2)) < 1e-5)
    face = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]); face /= np.linalg.norm(face, axis=1, keepdims=True)
    print(f"   corner normals all equal per triangle: {same}; max |corner normal - face normal (winding)| {np.linalg.norm(nors - face[:, None], axis=2).max():.2e}")
