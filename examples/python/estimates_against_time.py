#!/usr/bin/env python3
"""The paper's trade in one figure: relative MSE against time for the diffusion and the cone
estimates on the torus knot, each pass of each render measured against a long reference.

    python examples/python/estimates_against_time.py [OUT.png] [--quick]

Needs the dpm module (`pip install ./python`), NumPy and matplotlib. The reference is dpm's
own long run (cached next to OUT as OUT.reference.npy); `--quick` renders small and short.
"""

import pathlib
import sys
import time

import numpy as np

import dpm

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenes" / "torus-knot.toml"


def relative_mse(image, reference):
    """The mean over pixels of (e − r)² / (r² + ε²) of the RGB means, ε = 10% of the mean."""
    e, r = image.mean(axis=2), reference.mean(axis=2)
    eps = 0.1 * r.mean()
    return float(np.mean((e - r) ** 2 / (r**2 + eps**2)))


def curve(estimator, reference, passes, resolution):
    """Seconds since the start and relative MSE after each pass."""
    points, start = [], time.perf_counter()
    for image in dpm.Render(SCENE, passes=passes, resolution=resolution, estimator=estimator):
        points.append((time.perf_counter() - start, relative_mse(image, reference)))
    return points


def main():
    args = [a for a in sys.argv[1:] if a != "--quick"]
    quick = "--quick" in sys.argv[1:]
    out = pathlib.Path(args[0] if args else "estimates-against-time.png")
    resolution, passes, reference_passes = ((160, 120), 6, 24) if quick else ((400, 300), 24, 200)
    cached = out.with_suffix(".reference.npy")
    if cached.exists():
        reference = np.load(cached)
    else:
        reference = dpm.render(
            SCENE, passes=reference_passes, resolution=resolution, seed=99,
            estimator="epanechnikov",
        )
        np.save(cached, reference)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for estimator in ["diffusion", "cone"]:
        seconds, error = zip(*curve(estimator, reference, passes, resolution))
        ax.loglog(seconds, error, marker="o", label=estimator)
    ax.set_xlabel("seconds")
    ax.set_ylabel("relative MSE against the reference")
    ax.set_title("torus knot: error against time")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out)
    print(out)


if __name__ == "__main__":
    main()
