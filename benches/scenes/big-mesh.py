#!/usr/bin/env python3
"""Writes the big-mesh benchmark (BENCHMARKS.md, "Big meshes"): a bumpy sphere with about N
triangles, and a pbrt-v3 scene that shows it under one distant light.

    benches/scenes/big-mesh.py OUT_DIR [TRIANGLES] [--ascii]   (default 4,500,000; needs numpy)

Writes OUT_DIR/big-mesh.ply (positions, normals, uv; binary little endian, faces as uchar
counts and int indices, as pbrt's exporters write them) and OUT_DIR/big-mesh.pbrt, which both
dpm and pbrt-v3 render: `dpm render OUT_DIR/big-mesh.pbrt --passes 1 --spp 1`. With `--ascii`
it also writes the same mesh as text three ways: big-mesh-ascii.ply (an ASCII PLY) with
big-mesh-ascii.pbrt, big-mesh-inline.pbrt (a pbrt `trianglemesh`), and big-mesh.obj with
big-mesh-obj.toml (a dpm scene).
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


def ply_header(encoding, vertices, faces):
    return (
        f"ply\nformat {encoding} 1.0\n"
        f"element vertex {vertices}\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        "property float u\nproperty float v\n"
        f"element face {faces}\n"
        "property list uchar int vertex_indices\nend_header\n"
    )


def write_ply(path, pos, normals, uv, faces):
    header = ply_header("binary_little_endian", len(pos), len(faces))
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


def numbers(array, fmt):
    # One line a row, fields separated by spaces (np.savetxt into memory).
    import io

    text = io.StringIO()
    np.savetxt(text, array, fmt=fmt)
    return text.getvalue()


def write_atomically(path, text):
    with open(path + ".part", "w") as f:
        f.write(text)
    os.replace(path + ".part", path)


def write_text_meshes(out, pos, normals, uv, faces, scene):
    vertices = numbers(np.concatenate([pos, normals, uv], axis=1), "%.7g")
    header = ply_header("ascii", len(pos), len(faces))
    counted = np.concatenate([np.full((len(faces), 1), 3), faces], axis=1)
    write_atomically(
        os.path.join(out, "big-mesh-ascii.ply"), header + vertices + numbers(counted, "%d")
    )
    write_atomically(
        os.path.join(out, "big-mesh-ascii.pbrt"),
        scene.replace('"big-mesh.ply"', '"big-mesh-ascii.ply"'),
    )
    inline = (
        'Shape "trianglemesh" "integer indices" [\n'
        + numbers(faces, "%d")
        + ']\n"point3 P" [\n'
        + numbers(pos, "%.7g")
        + ']\n"normal N" [\n'
        + numbers(normals, "%.7g")
        + ']\n"float uv" [\n'
        + numbers(uv, "%.7g")
        + "]\n"
    )
    shape = 'Shape "plymesh" "string filename" "big-mesh.ply"\n'
    write_atomically(os.path.join(out, "big-mesh-inline.pbrt"), scene.replace(shape, inline))
    # OBJ counts from 1, and (u, v) and normals share the vertex's index.
    obj = (
        numbers(pos, "v %.7g %.7g %.7g")
        + numbers(normals, "vn %.7g %.7g %.7g")
        + numbers(uv, "vt %.7g %.7g")
        + numbers(np.repeat(faces + 1, 3, axis=1), "f %d/%d/%d %d/%d/%d %d/%d/%d")
    )
    write_atomically(os.path.join(out, "big-mesh.obj"), obj)
    toml = """# The big-mesh benchmark's mesh as an OBJ (benches/scenes/big-mesh.py --ascii).
[camera]
position = [0.0, 0.4, 3.2]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov_y = 40.0
resolution = [160, 120]

[[lights]]
type = "distant"
direction = [-1.0, -2.0, -3.0]
irradiance = [3.0, 3.0, 3.0]

[materials.clay]
type = "diffuse"
albedo = [0.6, 0.5, 0.4]

[[objects]]
type = "mesh"
file = "big-mesh.obj"
material = "clay"
"""
    write_atomically(os.path.join(out, "big-mesh-obj.toml"), toml)


def main():
    args = [a for a in sys.argv[1:] if a != "--ascii"]
    if not args:
        sys.exit(__doc__)
    out = args[0]
    triangles = int(args[1]) if len(args) > 1 else 4_500_000
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
    write_atomically(os.path.join(out, "big-mesh.pbrt"), scene)
    if "--ascii" in sys.argv[1:]:
        write_text_meshes(out, pos, normals, uv, faces, scene)
    print(f"{len(faces)} triangles, {len(pos)} vertices in {out}")


if __name__ == "__main__":
    main()
