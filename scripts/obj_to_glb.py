#!/usr/bin/python3
"""Convert a Wavefront OBJ triangle mesh into a binary glTF 2.0 file (GLB).

Writes one mesh with one triangle primitive: POSITION (float32 VEC3, with min/max), NORMAL
(area-weighted smooth vertex normals) and uint32 indices. Polygons are fan-triangulated; texture
coordinates and OBJ normals are ignored.

Optional placement (baked into the vertices):
  --y-up-to-z-up    rotate +90 degrees about x, so the OBJ's +y becomes +z (OBJ scans are usually y-up)
  --height H        uniform scale so the mesh is H metres tall (along z after the rotation)
  --center          centre the mesh in x and y and put its lowest point on z = 0

Used once to make scenes/assets/bunny.glb from the Stanford Bunny's `bun_zipper` scan as OBJ (Stanford 3D
Scanning Repository), saved as stanford-bunny.obj:
  /usr/bin/python3 scripts/obj_to_glb.py stanford-bunny.obj scenes/assets/bunny.glb \
      --y-up-to-z-up --height 0.6 --center
Needs numpy (Debian: python3-numpy, under /usr/bin/python3).
"""
import argparse
import json
import struct
import sys

try:
    import numpy as np
except ImportError:
    sys.exit("obj_to_glb.py: numpy is missing; run it with /usr/bin/python3 (Debian's python3-numpy)")


def read_obj(path):
    vertices, faces = [], []
    with open(path, "r", encoding="utf-8", errors="replace") as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                vertices.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                idx = []
                for p in parts[1:]:
                    i = int(p.split("/")[0])
                    idx.append(i - 1 if i > 0 else len(vertices) + i)
                for k in range(1, len(idx) - 1):
                    faces.append([idx[0], idx[k], idx[k + 1]])
    return np.asarray(vertices, dtype=np.float64), np.asarray(faces, dtype=np.int64).reshape(-1, 3)


def smooth_normals(positions, triangles):
    """Area-weighted vertex normals: the sum of the (unnormalised) face cross products."""
    a, b, c = (positions[triangles[:, k]] for k in range(3))
    face = np.cross(b - a, c - a)
    normals = np.zeros_like(positions)
    for k in range(3):
        np.add.at(normals, triangles[:, k], face)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.where(length > 0, normals / np.maximum(length, 1e-300), np.array([0.0, 0.0, 1.0]))
    return normals


def signed_volume(positions, triangles):
    a, b, c = (positions[triangles[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def write_glb(path, positions, normals, triangles, name="mesh"):
    pos = positions.astype("<f4")
    nrm = normals.astype("<f4")
    idx = triangles.astype("<u4").reshape(-1)
    blobs = [pos.tobytes(), nrm.tobytes(), idx.tobytes()]
    offsets, binary = [], b""
    for blob in blobs:
        offsets.append(len(binary))
        binary += blob
        binary += b"\0" * ((4 - len(binary) % 4) % 4)
    gltf = {
        "asset": {"version": "2.0", "generator": "caustics scripts/obj_to_glb.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": name}],
        "meshes": [{"name": name, "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "mode": 4}]}],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": offsets[0], "byteLength": len(blobs[0]), "target": 34962},
            {"buffer": 0, "byteOffset": offsets[1], "byteLength": len(blobs[1]), "target": 34962},
            {"buffer": 0, "byteOffset": offsets[2], "byteLength": len(blobs[2]), "target": 34963},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(pos), "type": "VEC3",
             "min": [float(x) for x in pos.min(axis=0)] if len(pos) else [0, 0, 0],
             "max": [float(x) for x in pos.max(axis=0)] if len(pos) else [0, 0, 0]},
            {"bufferView": 1, "componentType": 5126, "count": len(nrm), "type": "VEC3"},
            {"bufferView": 2, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
        ],
    }
    js = json.dumps(gltf, separators=(",", ":")).encode("utf-8")
    js += b" " * ((4 - len(js) % 4) % 4)
    total = 12 + 8 + len(js) + 8 + len(binary)
    with open(path, "wb") as f:
        f.write(struct.pack("<III", 0x46546C67, 2, total))
        f.write(struct.pack("<II", len(js), 0x4E4F534A))
        f.write(js)
        f.write(struct.pack("<II", len(binary), 0x004E4942))
        f.write(binary)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("obj")
    ap.add_argument("glb")
    ap.add_argument("--y-up-to-z-up", action="store_true")
    ap.add_argument("--height", type=float, default=0.0)
    ap.add_argument("--center", action="store_true")
    args = ap.parse_args()

    positions, triangles = read_obj(args.obj)
    if len(triangles) == 0:
        sys.exit(f"obj_to_glb.py: {args.obj} has no faces")
    used = np.unique(triangles)
    if args.y_up_to_z_up:
        positions = np.stack([positions[:, 0], -positions[:, 2], positions[:, 1]], axis=1)
    if args.height > 0:
        extent = positions[used, 2].max() - positions[used, 2].min()
        positions = positions * (args.height / extent)
    if args.center:
        lo, hi = positions[used].min(axis=0), positions[used].max(axis=0)
        positions = positions - np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])
    normals = smooth_normals(positions, triangles)
    write_glb(args.glb, positions, normals, triangles, name="mesh")
    lo, hi = positions[used].min(axis=0), positions[used].max(axis=0)
    print(f"{args.glb}: {len(positions)} vertices, {len(triangles)} triangles, bounds {lo.round(4).tolist()} .. "
          f"{hi.round(4).tolist()}, signed volume {signed_volume(positions, triangles):.6g} m^3")


if __name__ == "__main__":
    main()
