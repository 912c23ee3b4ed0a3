#!/usr/bin/env python3
"""Error of rendered images against a reference, as BENCHMARKS.md reports it.

    scripts/image-error.py REFERENCE IMAGE [IMAGE ...] [--box N] [--exclude-disc ROW COL R]
                           [--window ROW0 ROW1 COL0 COL1]

Prints, per IMAGE, the ratio of its mean to the reference's and the relative MSE (per pixel
(e − r)² / (r² + ε²), ε a tenth of the reference's mean, channels averaged first), over the
whole image, over the pixels outside the disc given by --exclude-disc (pixel row and column of
its centre, radius in pixels: a region the reference is known to lack, such as an object that
pbrt's bdpt sees specular–diffuse–specular paths through), and within --window. --box N boxes
the reference down by N first (a reference at N times the images' resolution). Reads EXR and
PFM (needs numpy and OpenEXR: pip install numpy OpenEXR).
"""

import sys

import numpy as np


def read(path):
    if path.endswith(".pfm"):
        with open(path, "rb") as f:
            kind = f.readline().strip()
            width, height = map(int, f.readline().split())
            scale = float(f.readline())
            data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
        channels = 3 if kind == b"PF" else 1
        image = data.reshape(height, width, channels)[::-1]
        return image.mean(-1).astype(np.float64)
    import Imath
    import OpenEXR

    f = OpenEXR.InputFile(path)
    window = f.header()["dataWindow"]
    width, height = window.max.x - window.min.x + 1, window.max.y - window.min.y + 1
    pixel = Imath.PixelType(Imath.PixelType.FLOAT)
    rgb = [np.frombuffer(f.channel(c, pixel), dtype=np.float32).reshape(height, width) for c in "RGB"]
    return np.mean(rgb, axis=0).astype(np.float64)


def option(args, name, count):
    if name not in args:
        return None
    i = args.index(name)
    values = args[i + 1 : i + 1 + count]
    del args[i : i + 1 + count]
    return [float(v) for v in values]


def main():
    args = sys.argv[1:]
    box = option(args, "--box", 1)
    disc = option(args, "--exclude-disc", 3)
    window = option(args, "--window", 4)
    if len(args) < 2:
        sys.exit(__doc__)
    reference = read(args[0])
    if box:
        n = int(box[0])
        h, w = reference.shape[0] // n, reference.shape[1] // n
        reference = reference[: h * n, : w * n].reshape(h, n, w, n).mean(axis=(1, 3))
    rows, cols = np.mgrid[0 : reference.shape[0], 0 : reference.shape[1]]
    keep = np.ones(reference.shape, dtype=bool)
    if disc:
        keep = (rows + 0.5 - disc[0]) ** 2 + (cols + 0.5 - disc[1]) ** 2 > disc[2] ** 2
    inside = np.zeros(reference.shape, dtype=bool)
    if window:
        r0, r1, c0, c1 = map(int, window)
        inside[r0:r1, c0:c1] = True
        inside &= keep
    eps = 0.1 * reference.mean()
    for path in args[1:]:
        image = read(path)
        if image.shape != reference.shape:
            sys.exit(f"{path}: {image.shape} pixels, the reference {reference.shape}")
        error = (image - reference) ** 2 / (reference**2 + eps**2)
        line = f"{path}: mean ÷ reference {image[keep].mean() / reference[keep].mean():.4f}, "
        line += f"relative MSE {error.mean():.5f}"
        if disc:
            line += f", outside the disc {error[keep].mean():.5f}"
        if window:
            line += f", in the window {error[inside].mean():.5f}"
        print(line)


if __name__ == "__main__":
    main()
