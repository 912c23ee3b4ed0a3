#!/usr/bin/env python3
"""Where a glossy lobe should stop reading photons (docs/materials.md, "The glossy threshold").

    scripts/glossy-threshold.py DPM OUT_DIR [--alphas A,...] [--size WxH] [--time S]
        [--reference-time S]

A Cornell box whose floor is a rough silver conductor of Trowbridge-Reitz alpha A, with a
smooth glass sphere focusing the ceiling light into a caustic on that floor and an orange
plastic sphere (scenes/cornell-materials.pbrt's walls and light). For each A, dpm renders the
scene with the floor's lobe read from photons (`--glossy-min-alpha 0`) and followed
(`--glossy-min-alpha 100`), each for --time seconds, and reports both relative MSEs against a
reference: the mean of a --reference-time run of each way (both are consistent here: the light
is an area light, which a followed ray can reach through the glass), with the relative MSE
between those two long runs as the reference's own uncertainty. Run with nothing else on the
machine: the equal-time figures are wall-clock.
"""

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def arg(flags, name, default):
    if name in flags:
        i = flags.index(name)
        value = flags[i + 1]
        del flags[i : i + 2]
        return value
    return default


def scene(alpha):
    base = (ROOT / "scenes" / "cornell-materials.pbrt").read_text()
    head = base[: base.index("WorldBegin")]
    world = base[base.index("WorldBegin") :]
    # The walls and light as they are; the floor becomes the conductor, the spheres a smooth
    # glass ball and the plastic one.
    floor = ("# floor\nShape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
             "  \"point3 P\" [-1 0 -1  -1 0 1  1 0 1  1 0 -1]\n")
    assert floor in world, "scenes/cornell-materials.pbrt changed: update this script"
    silver = ("AttributeBegin\n  Material \"metal\" \"rgb eta\" [0.16 0.14 0.13] \"rgb k\" [4.0 3.6 2.7]\n"
              f"    \"float roughness\" {alpha} \"bool remaproughness\" \"false\"\n"
              f"  {floor}AttributeEnd\n")
    world = world.replace(floor, "")
    spheres = world[world.index("AttributeBegin\n  Material \"plastic\"") : world.index("WorldEnd")]
    ball = ("AttributeBegin\n  Material \"plastic\" \"rgb Kd\" [0.55 0.25 0.08] \"rgb Ks\" [0.5 0.5 0.5]\n"
            "    \"float roughness\" 0.2 \"bool remaproughness\" \"false\"\n"
            "  Translate -0.5 0.3 -0.45\n  Shape \"sphere\" \"float radius\" 0.3\nAttributeEnd\n"
            "AttributeBegin\n  Material \"glass\" \"float index\" 1.5\n"
            "  Translate 0.2 0.45 0.1\n  Shape \"sphere\" \"float radius\" 0.35\nAttributeEnd\n")
    world = world.replace(spheres, silver + ball)
    return head + world


def render(dpm, path, out, size, seconds, split, reference=None):
    stats = out.with_suffix(".json")
    cmd = [dpm, "render", str(path), "-o", str(out), "--resolution", size, "--time", str(seconds),
           "--glossy-min-alpha", str(split), "--stats", str(stats)]
    if reference:
        cmd += ["--reference", str(reference)]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return json.loads(stats.read_text())


def image_error(image, reference):
    tool = ROOT / "target" / "release" / "examples" / "image_error"
    if not tool.exists():
        subprocess.run(["cargo", "build", "--release", "--example", "image_error", "--example", "compare_images"],
                       cwd=ROOT, check=True)
    out = subprocess.run([str(tool), str(image), str(reference)], check=True, capture_output=True, text=True)
    return float(out.stdout.strip())


def mean_image(a, b, out):
    subprocess.run(["oiiotool", str(a), str(b), "--add", "--mulc", "0.5", "-o", str(out)], check=True)


def main():
    flags = sys.argv[1:]
    alphas = [float(a) for a in arg(flags, "--alphas", "0.02,0.05,0.1,0.2,0.4").split(",")]
    size = arg(flags, "--size", "160x160")
    seconds = float(arg(flags, "--time", "10"))
    reference_time = float(arg(flags, "--reference-time", "120"))
    if len(flags) != 2:
        sys.exit(__doc__)
    dpm, out = flags[0], Path(flags[1])
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for alpha in alphas:
        path = out / f"floor-{alpha}.pbrt"
        path.write_text(scene(alpha))
        long = {}
        for name, split in (("estimated", 0), ("followed", 100)):
            image = out / f"ref-{alpha}-{name}.exr"
            if not image.exists():
                render(dpm, path, image, size, reference_time, split)
            long[name] = image
        reference = out / f"ref-{alpha}.exr"
        mean_image(long["estimated"], long["followed"], reference)
        spread = image_error(long["estimated"], long["followed"])
        row = {"alpha": alpha, "reference_spread": spread}
        for name, split in (("estimated", 0), ("followed", 100)):
            stats = render(dpm, path, out / f"{alpha}-{name}.exr", size, seconds, split, reference)
            last = stats["per_pass"][-1]
            row[name] = last["relative_mse"]
            row[name + "_passes"] = len(stats["per_pass"])
        rows.append(row)
        print(json.dumps(row), flush=True)
    (out / "threshold.json").write_text(json.dumps(rows, indent=1))
    print(f"\n| floor α | read from photons | followed | long runs apart |\n|---|---|---|---|")
    for r in rows:
        print(f"| {r['alpha']} | {r['estimated']:.3e} ({r['estimated_passes']} passes) | "
              f"{r['followed']:.3e} ({r['followed_passes']} passes) | {r['reference_spread']:.1e} |")


if __name__ == "__main__":
    main()
