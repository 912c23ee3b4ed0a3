#!/usr/bin/env python3
"""Error against time for dpm and pbrt-v3's SPPM on one pbrt scene, side by side (BENCHMARKS.md,
"Peers side by side").

    scripts/sppm-side-by-side.py PBRT DPM SCENE.pbrt REFERENCE.exr OUT_DIR
        [--size WxH] [--photons N] [--radii R,...] [--iterations N,...] [--dpm-time S]
        [--repeat N] [-- DPM_FLAGS...]

PBRT is a pbrt-v3 binary (built by the reader from pbrt's public source; nothing here builds
it), DPM a dpm binary. SCENE is rendered by both at --size: by pbrt with its Integrator line
replaced by SPPM at every radius and iteration count (--photons photons an iteration,
maxdepth 16), each run timed by its wall clock; by dpm with `--time S --reference REFERENCE
--stats`, whose per-pass record gives its whole error-against-time curve in one run. The error
is dpm's relative MSE (examples/image_error.rs; the mean over pixels of (e - r)^2/(r^2 + eps^2)
of the RGB means, eps = 10% of the reference's mean). With --repeat N every run is made N times
in turn and its time is the median. Prints a table per renderer and writes OUT_DIR/runs.json.
Run it with nothing else on the machine: the figures are wall-clock times.
"""

import json
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path


def arg(flags, name, default):
    if name in flags:
        i = flags.index(name)
        value = flags[i + 1]
        del flags[i : i + 2]
        return value
    return default


def image_error(tool, image, reference):
    out = subprocess.run([tool, str(image), str(reference)], check=True, capture_output=True, text=True)
    return float(out.stdout.strip())


def main():
    args = sys.argv[1:]
    dpm_flags = []
    if "--" in args:
        i = args.index("--")
        args, dpm_flags = args[:i], args[i + 1 :]
    size = arg(args, "--size", "256x256")
    photons = int(arg(args, "--photons", "100000"))
    radii = [float(r) for r in arg(args, "--radii", "0.025,0.05,0.1").split(",")]
    iterations = [int(n) for n in arg(args, "--iterations", "4,8,16,32,64,128").split(",")]
    dpm_time = float(arg(args, "--dpm-time", "40"))
    repeat = int(arg(args, "--repeat", "1"))
    if len(args) != 5:
        sys.exit(__doc__)
    pbrt, dpm, scene, reference, out = args[0], args[1], Path(args[2]), Path(args[3]), Path(args[4])
    out.mkdir(parents=True, exist_ok=True)
    tool = Path(dpm).parent / "examples" / "image_error"
    if not tool.exists():
        sys.exit(f"{tool} is missing: cargo build --release --example image_error")
    width, height = size.split("x")
    text = scene.read_text()
    text = re.sub(r'^Film .*?(?=^\S)', f'Film "image" "integer xresolution" [{width}] '
                  f'"integer yresolution" [{height}]\n', text, flags=re.S | re.M)
    runs = []

    for round_ in range(repeat):
        for radius in radii:
            for n in iterations:
                body = re.sub(r'^Integrator .*$', f'Integrator "sppm" "integer numiterations" [{n}] '
                              f'"integer photonsperiteration" [{photons}] "float radius" [{radius}] '
                              '"integer maxdepth" [16]', text, flags=re.M)
                file = scene.parent / f".sppm-{radius}-{n}.pbrt"
                file.write_text(body)
                image = out / f"sppm-{radius}-{n}.exr"
                start = time.monotonic()
                subprocess.run([pbrt, "--quiet", "--outfile", str(image), str(file)], check=True)
                seconds = time.monotonic() - start
                file.unlink()
                runs.append({"renderer": "pbrt-v3 sppm", "radius": radius, "iterations": n,
                             "photons": photons, "round": round_, "seconds": seconds,
                             "relative_mse": image_error(tool, image, reference)})
                print(f"sppm r={radius} {n}x{photons}: {seconds:.2f} s, {runs[-1]['relative_mse']:.3e}", flush=True)
        stats = out / f"dpm-{round_}.json"
        cmd = [dpm, "render", str(scene), "-o", str(out / "dpm.exr"), "--resolution", size,
               "--time", str(dpm_time), "--reference", str(reference), "--stats", str(stats)] + dpm_flags
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for p in json.loads(stats.read_text())["per_pass"]:
            runs.append({"renderer": "dpm", "pass": p["pass"], "round": round_,
                         "seconds": p["elapsed"], "relative_mse": p["relative_mse"]})
        print(f"dpm: {len(runs) - sum(r['renderer'] != 'dpm' for r in runs)} pass records", flush=True)

    (out / "runs.json").write_text(json.dumps(runs, indent=1))
    key = lambda r: (r["renderer"], r.get("radius"), r.get("iterations"), r.get("pass"))
    groups = {}
    for r in runs:
        groups.setdefault(key(r), []).append(r)
    print("\n| renderer | setting | seconds (median) | relative MSE |\n|---|---|---|---|")
    for k, rs in sorted(groups.items(), key=lambda kv: (kv[0][0], kv[0][1] or 0, kv[0][2] or 0, kv[0][3] or 0)):
        seconds = statistics.median(r["seconds"] for r in rs)
        setting = (f"r {k[1]}, {k[2]} x {photons}" if k[0] != "dpm" else f"after pass {k[3]}")
        print(f"| {k[0]} | {setting} | {seconds:.2f} | {rs[0]['relative_mse']:.3e} |")


if __name__ == "__main__":
    main()
