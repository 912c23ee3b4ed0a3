#!/usr/bin/env python3
"""Writes the big-mesh benchmark (BENCHMARKS.md, "Loading big meshes"): one binary PLY of a
bumpy sphere with about N triangles, and a pbrt-v3 scene that shows it under one distant light.

    benches/scenes/big-mesh.py OUT_DIR [TRIANGLES]   (default 4,500,000; needs numpy)

Writes OUT_DIR/big-mesh.ply (positions, normals, uv; binary little endian, faces as uchar
counts and int indices, as pbrt's exporters write them) and OUT_DIR/big-mesh.pbrt, which both
dpm and pbrt-v3 render: `dpm render OUT_DIR/big-mesh.pbrt --passes 1 --spp 1`.
"""

import os
import sys

import numpy as np


def sphere_grid(triangles):
    # A latitude-longitude grid of rows × 2·rows quads, two triangles each.
    rows = max(4, int(round((triangles / 4) ** 0.5)))
    cols = 2 * rows
    theta = (np.arange(rows + 1) / rows) * np.pi
    phi = (np.arange(cols + 1) / cols) * 2 * np.pi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    # Bumps keep the BVH honest: no two triangles alike.
    r = 1.0 + 0.03 * np.sin(23 * t) * np.cos(17 * p)
    n = np.stack([np.sin(t) * np.cos(p), np.cos(t), np.sin(t) * np.sin(p)], axis=-1)
    pos = (n * r[..., None]).reshape(-1, 3).astype("<f4")
    normals = n.reshape(-1, 3).astype("<f4")
    uv = np.stack([p / (2 * np.pi), t / np.pi], axis=-1).reshape(-1, 2).astype("<f4")
    i, j = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    a = (i * (cols + 1) + j).ravel()
    b, c, d = a + 1, a + cols + 1, a + cols + 2
    faces = np.concatenate([np.stack([a, c, b], -1), np.stack([b, c, d], -1)]).astype("<i4")
    return pos, normals, uv, faces


def write_ply(path, pos, normals, uv, faces):
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(pos)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        "property float u\nproperty float v\n"
        f"element face {len(faces)}\n"
        "property list uchar int vertex_indices\nend_header\n"
    )
    vertices = np.concatenate([pos, normals, uv], axis=1).astype("<f4")
    records = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
    records["n"] = 3
    records["i"] = faces
    tmp = path + ".part"
    with open(tmp, "wb") as f:
        f.write(header.encode())
        f.write(vertices.tobytes())
        f.write(records.tobytes())
    os.replace(tmp, path)


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    triangles = int(sys.argv[2]) if len(sys.argv) > 2 else 4_500_000
    os.makedirs(out, exist_ok=True)
    pos, normals, uv, faces = sphere_grid(triangles)
    write_ply(os.path.join(out, "big-mesh.ply"), pos, normals, uv, faces)
    scene = """LookAt 0 0.4 3.2  0 0 0  0 1 0
Camera "perspective" "float fov" [40]
Sampler "random" "integer pixelsamples" [1]
Integrator "path" "integer maxdepth" [2]
Film "image" "integer xresolution" [160] "integer yresolution" [120] "string filename" "big-mesh.exr"
WorldBegin
LightSource "distant" "point from" [1 2 3] "point to" [0 0 0] "rgb L" [3 3 3]
Material "matte" "rgb Kd" [0.6 0.5 0.4]
Shape "plymesh" "string filename" "big-mesh.ply"
WorldEnd
"""
    with open(os.path.join(out, "big-mesh.pbrt"), "w") as f:
        f.write(scene)
    print(f"{len(faces)} triangles, {len(pos)} vertices in {out}")


if __name__ == "__main__":
    main()
