#!/usr/bin/env python3
"""dpm against pbrt-v3's SPPM at equal time on one pbrt scene, against a long reference: the whole
image's and a region's relative MSE, the image mean and every 50x50 block's mean over the
reference's (BENCHMARKS.md, "Caustic-glass against pbrt" and "Materials against pbrt").

    scripts/equal-time.py PBRT DPM SCENE.pbrt REFERENCE.exr OUT_DIR
        [--sppm R:N,R:N,...] [--photons N] [--dpm-times S,S,...] [--maxdepth D]
        [--region caustic|none] [--region-from IMAGE.exr] [--block B] [-- DPM_FLAGS...]

PBRT is a pbrt-v3 binary (built by the reader from pbrt's public source; nothing here builds
it), DPM a dpm binary. The scene's Film line sets the size; both renderers render it as written
but for the Integrator line, which becomes SPPM (--photons photons an iteration, maxdepth D) at
each radius R and iteration count N of --sppm, each run timed by its wall clock. dpm renders it
with `--time S` for each S of --dpm-times (and DPM_FLAGS), its time the wall clock too.

The error is the relative MSE of examples/image_error.rs (the mean over pixels of
(e - r)^2/(r^2 + eps^2) of the RGB means, eps = 10% of the reference's mean). The region
"caustic" is the set of pixels where the caustic layer of dpm's longest run carries at least a
quarter of the pixel (its image mean), or of IMAGE.exr's (--region-from: to compare dpm's
settings over one region); its error is the same sum over those pixels only, with the same eps.
`--sppm none` renders dpm alone. Blocks the reference leaves darker than 1% of its mean are left out of the
block range. pbrt-v3 has no seed: an SPPM run draws the same camera samples and photons as the
first iterations of an SPPM reference, so its error against that reference is flattered; make
the reference many times longer than the longest run it judges. Needs numpy and OpenEXR (pip
install numpy OpenEXR). Run it with nothing else on
the machine: the figures are wall-clock times.
"""

import json
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import OpenEXR


def arg(flags, name, default):
    if name in flags:
        i = flags.index(name)
        value = flags[i + 1]
        del flags[i : i + 2]
        return value
    return default


def read(path, prefix=""):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = f.channels()
        rgb = [np.asarray(ch[prefix + c].pixels, dtype=np.float64) for c in "RGB"]
        return sum(rgb) / 3.0


def figures(image, reference, region, block):
    e, r = read(image), read(reference)
    eps2 = max((0.1 * r.mean()) ** 2, np.finfo(float).tiny)
    err = (e - r) ** 2 / (r * r + eps2)
    out = {"relative_mse": float(err.mean()), "mean_ratio": float(e.mean() / r.mean())}
    if region is not None:
        out["region_relative_mse"] = float(err[region].mean())
    ratios = []
    h, w = r.shape
    for y in range(0, h - block + 1, block):
        for x in range(0, w - block + 1, block):
            rb = r[y : y + block, x : x + block].mean()
            if rb > 0.01 * r.mean():
                ratios.append(e[y : y + block, x : x + block].mean() / rb)
    out["block_min"], out["block_max"] = float(min(ratios)), float(max(ratios))
    return out


def main():
    args = sys.argv[1:]
    dpm_flags = []
    if "--" in args:
        i = args.index("--")
        args, dpm_flags = args[:i], args[i + 1 :]
    sppm_arg = arg(args, "--sppm", "0.075:40")
    sppm = [] if sppm_arg == "none" else [(float(a), int(b)) for a, b in (s.split(":") for s in sppm_arg.split(","))]
    region_from = arg(args, "--region-from", None)
    photons = int(arg(args, "--photons", "175000"))
    dpm_times = [float(t) for t in arg(args, "--dpm-times", "10,30,100").split(",")]
    maxdepth = int(arg(args, "--maxdepth", "16"))
    region_name = arg(args, "--region", "caustic")
    block = int(arg(args, "--block", "50"))
    if len(args) != 5:
        sys.exit(__doc__)
    pbrt, dpm, scene, reference, out = args[0], args[1], Path(args[2]), Path(args[3]), Path(args[4])
    out.mkdir(parents=True, exist_ok=True)
    runs = []

    for t in dpm_times:
        image = out / f"dpm-{t:g}{'-' + '_'.join(f.strip('-') for f in dpm_flags) if dpm_flags else ''}.exr"
        start = time.monotonic()
        subprocess.run([dpm, "render", str(scene), "-o", str(image), "--time", str(t)] + dpm_flags,
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        runs.append({"renderer": "dpm", "setting": f"--time {t:g}", "image": image,
                     "seconds": time.monotonic() - start})
        print(f"dpm --time {t:g}: {runs[-1]['seconds']:.1f} s", flush=True)
    text = scene.read_text()
    for radius, n in sppm:
        body = re.sub(r'^Integrator .*?(?=^\S)', f'Integrator "sppm" "integer numiterations" [{n}] '
                      f'"integer photonsperiteration" [{photons}] "float radius" [{radius}] '
                      f'"integer maxdepth" [{maxdepth}]\n', text, flags=re.S | re.M)
        file = scene.parent / f".sppm-{radius}-{n}.pbrt"
        file.write_text(body)
        image = out / f"sppm-{radius}-{n}.exr"
        start = time.monotonic()
        subprocess.run([pbrt, "--quiet", "--outfile", str(image), str(file)], check=True)
        file.unlink()
        runs.append({"renderer": "pbrt-v3 sppm", "setting": f"r {radius}, {n} x {photons}",
                     "image": image, "seconds": time.monotonic() - start})
        print(f"sppm r {radius} {n}x{photons}: {runs[-1]['seconds']:.1f} s", flush=True)

    region = None
    if region_name == "caustic":
        source = region_from or max((r for r in runs if r["renderer"] == "dpm"), key=lambda r: r["seconds"])["image"]
        caustic, whole = read(source, "caustic."), read(source)
        region = caustic >= 0.25 * np.maximum(whole, 1e-30)
        print(f"caustic region: {region.mean():.3%} of the pixels", flush=True)
    print("\n| renderer | setting | seconds | relative MSE | relative MSE, "
          f"{region_name} | mean / reference | {block}x{block} blocks / reference |\n|---|---|---|---|---|---|---|")
    for r in runs:
        r.update(figures(r["image"], reference, region, block))
        r["image"] = str(r["image"])
        print(f"| {r['renderer']} | {r['setting']} | {r['seconds']:.1f} | {r['relative_mse']:.2e} | "
              f"{r.get('region_relative_mse', float('nan')):.2e} | {r['mean_ratio']:.4f} | "
              f"{r['block_min']:.3f}-{r['block_max']:.3f} |")
    (out / "runs.json").write_text(json.dumps(runs, indent=1))


if __name__ == "__main__":
    main()
