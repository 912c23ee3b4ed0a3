#!/usr/bin/env python3
"""How much of a pbrt scene collection dpm opens (docs/scene-format.md, "The pbrt-v3 scene
collection, measured").

    scripts/pbrt-collection.py COLLECTION DPM OUT.md [--size WxH] [--timeout S]

COLLECTION is a checkout of a scene collection (for instance disini/pbrt-v3-scenes; nothing here
fetches it), DPM a dpm binary. Every .pbrt file one folder deep that holds `WorldBegin` is read
by `dpm check`; each that would render is then rendered once, tiny (--size, 1 pass), under
`/usr/bin/time -v` with a wall-clock limit of --timeout seconds. Each scene's files (every
`Include`, mesh, image and BSDF table it names, Film outputs aside) are looked for first, so
that a scene refused for its material before a missing mesh is read still counts as
incomplete. Writes a Markdown table (scene, files, outcome, first refusal, render seconds, peak
resident MiB) to OUT.md and a summary to standard output.
"""

import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def arg(flags, name, default):
    if name in flags:
        i = flags.index(name)
        value = flags[i + 1]
        del flags[i : i + 2]
        return value
    return default


def scenes(collection):
    for path in sorted(collection.glob("*/*.pbrt")):
        try:
            if "WorldBegin" in path.read_text(errors="replace"):
                yield path
        except OSError:
            continue


DIRECTIVE = re.compile(r"\b(Film|Shape|Texture|LightSource|Material|MakeNamedMaterial|"
                       r"MakeNamedMedium|Include|Import|AreaLightSource|Camera|Sampler)\b")
NAMED_FILE = re.compile(r'"string\s+(filename|mapname|bsdffile)"\s*\[?\s*"([^"]+)"')
INCLUDE = re.compile(r'^\s*(?:Include|Import)\s+"([^"]+)"', re.M)


def absent_files(path, seen=None):
    """The files `path` names (recursively through its includes) that do not exist."""
    seen = set() if seen is None else seen
    absent = []
    text = path.read_text(errors="replace")
    for m in NAMED_FILE.finditer(text):
        before = [d.group(1) for d in DIRECTIVE.finditer(text, 0, m.start())]
        if before and before[-1] == "Film":
            continue
        named = path.parent / m.group(2)
        if not named.exists():
            absent.append(named)
    for m in INCLUDE.finditer(text):
        named = path.parent / m.group(1)
        if not named.exists():
            absent.append(named)
        elif named.resolve() not in seen:
            seen.add(named.resolve())
            absent += absent_files(named, seen)
    return absent


def first_error(text):
    for line in text.splitlines():
        if line.startswith("error: "):
            message = line[len("error: ") :]
            # The place names the checkout; the table names the scene.
            return re.sub(r"^\S*?/([^/]+/[^/:]+(:\d+)*): ", r"\1: ", message)
    return ""


def main():
    args = sys.argv[1:]
    size = arg(args, "--size", "64x64")
    timeout = float(arg(args, "--timeout", "300"))
    if len(args) != 3:
        sys.exit(__doc__)
    collection, dpm, out = Path(args[0]), args[1], Path(args[2])
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for scene in scenes(collection):
            name = scene.relative_to(collection).as_posix()
            absent = sorted({p.relative_to(collection).as_posix() for p in absent_files(scene)})
            files = "all present" if not absent else f"{len(absent)} absent: {absent[0]}"
            check = subprocess.run([dpm, "check", str(scene)], capture_output=True, text=True)
            if check.returncode != 0:
                refusal = first_error(check.stdout + check.stderr) or f"exit {check.returncode}"
                if check.returncode not in (0, 2):
                    refusal = f"CRASH (exit {check.returncode}): {refusal}"
                rows.append((name, files, "refused", refusal, "", ""))
                continue
            media = "medium-boundary" in check.stdout + check.stderr
            outcome = "renders, media left out" if media else "renders"
            image = Path(tmp) / "image.png"
            command = ["/usr/bin/time", "-v", dpm, "render", str(scene), "-o", str(image),
                       "--resolution", size, "--passes", "1"]
            start = time.monotonic()
            try:
                run = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
            except subprocess.TimeoutExpired:
                rows.append((name, files, "timed out", f"over {timeout:.0f} s", "", ""))
                continue
            seconds = time.monotonic() - start
            peak = re.search(r"Maximum resident set size \(kbytes\): (\d+)", run.stderr)
            mib = f"{int(peak.group(1)) / 1024:.0f}" if peak else ""
            if run.returncode == 0:
                rows.append((name, files, outcome, "", f"{seconds:.1f}", mib))
            else:
                rows.append((name, files, f"render failed (exit {run.returncode})", first_error(run.stderr), f"{seconds:.1f}", mib))
    complete = [r for r in rows if r[1] == "all present"]
    renders = sum(1 for r in complete if r[2].startswith("renders"))
    lines = [
        "| scene | files | outcome | first refusal | render s | peak MiB |",
        "|---|---|---|---|---|---|",
    ]
    for row in rows:
        lines.append("| " + " | ".join(c.replace("|", "\\|") for c in row) + " |")
    out.write_text("\n".join(lines) + "\n")
    print(f"{len(rows)} scenes, {len(complete)} with all their files; of those {renders} render "
          f"({size}, 1 pass); table in {out}")


if __name__ == "__main__":
    main()
