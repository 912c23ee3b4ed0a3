#!/usr/bin/env python3
"""dpm against pbrt's own renders of a pbrt scene collection (docs/scene-format.md, "dpm
against pbrt's images").

    scripts/pbrt-fidelity.py COLLECTION DPM OUT [--pixels N] [--only NAME,NAME]
                             [--references DIR] [-- DPM_FLAGS...]

COLLECTION is a checkout of a scene collection with pbrt's renders under images/ (for instance
disini/pbrt-v3-scenes; nothing here fetches it), DPM a dpm binary. Every .pbrt file one folder
deep whose Film names an image that exists as images/FOLDER/NAME.exr, and that `dpm check`
would render, is rendered by dpm at its defaults (and DPM_FLAGS) as pbrt reads it (a file
without an Integrator line gets pbrt's default, --pbrt-default-integrator) at the film's resolution
divided by the smallest whole factor that leaves at most --pixels (120,000) pixels in the
image; pbrt's image is boxed down by the same factor. Writes OUT/table.md (scene, pbrt's
integrator and maxdepth, dpm's seconds and passes, each channel's mean over pbrt's, the
relative MSE, and the 16-px blocks that differ by more than 5% and by more than 4 sigma of the
two images' own noise: of all blocks and of the bright ones, whose reference mean is at least
a tenth of the image's) and OUT/NAME.png per scene: pbrt | dpm | their difference (grey is
equal, red dpm brighter, blue darker, full at a factor of 2). Needs numpy, OpenEXR and Pillow
(pip install numpy OpenEXR Pillow). The times are wall-clock: run it with nothing else on the
machine. --references DIR compares against DIR/FOLDER/NAME.exr instead of the collection's
images (a pbrt build's own renders of the files, at the film's size or any whole fraction of
it), each boxed down to dpm's size.
"""

import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import OpenEXR
from PIL import Image

BLOCK = 16
INTEGRATOR = re.compile(r'^\s*Integrator\s+"([^"]+)"([^\n]*(?:\n\s*"[^\n]*)*)', re.M)
FILM = re.compile(r'^\s*Film\s+"[^"]+"(.*?)(?=^\s*[A-Z][A-Za-z]+\s)', re.M | re.S)


def arg(flags, name, default):
    if name in flags:
        i = flags.index(name)
        value = flags[i + 1]
        del flags[i : i + 2]
        return value
    return default


def read_rgb(path):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        ch = f.channels()
        return np.stack([np.asarray(ch[c].pixels, dtype=np.float64) for c in "RGB"], -1)


def box(image, factor):
    h, w = (image.shape[0] // factor) * factor, (image.shape[1] // factor) * factor
    image = image[:h, :w]
    return image.reshape(h // factor, factor, w // factor, factor, 3).mean(axis=(1, 3))


def film(text):
    """The film's resolution and output name, pbrt's defaults where the Film line gives none."""
    m = FILM.search(text + "\nEnd ")
    params = m.group(1) if m else ""

    def number(name, default):
        n = re.search(r'"integer\s+' + name + r'"\s*\[?\s*(\d+)', params)
        return int(n.group(1)) if n else default

    name = re.search(r'"string\s+filename"\s*\[?\s*"([^"]+)"', params)
    return number("xresolution", 640), number("yresolution", 480), name.group(1) if name else None


def integrator(text):
    m = INTEGRATOR.search(text)
    if not m:
        return "none (path)", "5"
    depth = re.search(r'"integer\s+maxdepth"\s*\[?\s*(\d+)', m.group(2))
    return m.group(1), depth.group(1) if depth else "5"


def block_means(image):
    """Per 16-px block: the mean over pixels and channels, and that mean's standard error."""
    y = image.mean(axis=2)
    h, w = (y.shape[0] // BLOCK) * BLOCK, (y.shape[1] // BLOCK) * BLOCK
    b = y[:h, :w].reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK)
    return b.mean(axis=(1, 3)), b.std(axis=(1, 3)) / BLOCK


def compare(reference, image):
    h, w = min(reference.shape[0], image.shape[0]), min(reference.shape[1], image.shape[1])
    r, e = reference[:h, :w], image[:h, :w]
    ratios = [e[..., c].mean() / max(r[..., c].mean(), 1e-30) for c in range(3)]
    rm, em = r.mean(axis=2), e.mean(axis=2)
    eps2 = max((0.1 * rm.mean()) ** 2, 1e-30)
    rel_mse = float(((em - rm) ** 2 / (rm * rm + eps2)).mean())
    (rb, rs), (eb, es) = block_means(r), block_means(e)
    differs = (np.abs(eb - rb) > 0.05 * np.maximum(rb, 1e-30)) & (
        np.abs(eb - rb) > 4.0 * np.sqrt(rs * rs + es * es)
    )
    bright = rb >= 0.1 * rb.mean()
    return ratios, rel_mse, differs, bright, r, e


def picture(reference, image, path):
    def tone(x):
        return np.clip((x / (1.0 + x)) ** (1 / 2.2) * 255, 0, 255).astype(np.uint8)

    ratio = np.log2(np.maximum(image.mean(axis=2), 1e-6) / np.maximum(reference.mean(axis=2), 1e-6))
    t = np.clip(ratio, -1, 1)
    diff = np.stack([0.5 + 0.5 * np.maximum(t, 0), 0.5 - 0.5 * np.abs(t), 0.5 + 0.5 * np.maximum(-t, 0)], -1)
    row = np.concatenate([tone(reference), tone(image), (diff * 255).astype(np.uint8)], axis=1)
    tmp = path.with_suffix(".tmp.png")
    Image.fromarray(row).save(tmp)
    tmp.replace(path)


def main():
    args = sys.argv[1:]
    extra = []
    if "--" in args:
        i = args.index("--")
        args, extra = args[:i], args[i + 1 :]
    pixels = int(arg(args, "--pixels", "120000"))
    only = arg(args, "--only", None)
    references = arg(args, "--references", None)
    if len(args) != 3:
        sys.exit(__doc__)
    collection, dpm, out = Path(args[0]), args[1], Path(args[2])
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for scene in sorted(collection.glob("*/*.pbrt")):
        text = scene.read_text(errors="replace")
        if "WorldBegin" not in text:
            continue
        width, height, output = film(text)
        if output is None:
            continue
        reference_path = collection / "images" / scene.parent.name / (Path(output).stem + ".exr")
        name = scene.relative_to(collection).as_posix()
        if not reference_path.exists() or (only and scene.stem not in only.split(",")):
            continue
        if subprocess.run([dpm, "check", str(scene)], capture_output=True).returncode != 0:
            continue
        reference = read_rgb(reference_path)
        factor = 1
        while (reference.shape[0] // factor) * (reference.shape[1] // factor) > pixels:
            factor += 1
        shown_width = reference.shape[1] // factor
        if references:
            reference = read_rgb(Path(references) / reference_path.relative_to(collection / "images"))
        reference_factor = max(reference.shape[1] // shown_width, 1)
        image_path = out / (scene.stem + ".exr")
        command = [dpm, "render", str(scene), "-o", str(image_path),
                   "--pbrt-default-integrator",
                   "--resolution", f"{width // factor}x{height // factor}"] + extra
        start = time.monotonic()
        run = subprocess.run(command, capture_output=True, text=True)
        seconds = time.monotonic() - start
        kind, depth = integrator(text)
        if run.returncode != 0:
            rows.append(f"| {name} | {kind} | {depth} | failed (exit {run.returncode}) |||||")
            continue
        passes = re.search(r"\((\d+) passes?", run.stderr + run.stdout)
        ratios, rel_mse, differs, bright, r, e = compare(box(reference, reference_factor), read_rgb(image_path))
        picture(r, e, out / (scene.stem + ".png"))
        rows.append(
            f"| {name} | {kind} | {depth} | {factor} | {seconds:.1f} | {passes.group(1) if passes else '?'} | "
            + " / ".join(f"{x:.3f}" for x in ratios)
            + f" | {rel_mse:.4f} | {int(differs.sum())} of {differs.size} | "
            f"{int((differs & bright).sum())} of {int(bright.sum())} |"
        )
        print(rows[-1], flush=True)
    table = [
        "| scene | pbrt's integrator | maxdepth | factor | dpm s | passes | dpm ÷ pbrt, R / G / B mean "
        "| relative MSE | 16-px blocks off | bright blocks off |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ] + rows
    (out / "table.md").write_text("\n".join(table) + "\n")
    print(f"{len(rows)} scenes; table in {out / 'table.md'}")


if __name__ == "__main__":
    main()
