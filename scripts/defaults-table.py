#!/usr/bin/env python3
"""Measures render settings against references, for choosing the defaults (BENCHMARKS.md,
"Whole scenes: the defaults").

    scripts/defaults-table.py DIR OLD_DPM NEW_DPM SCENE[,SCENE...] [CONFIG ...]

DIR holds SCENE.toml and SCENE-ref.pfm for each scene (the references: long progressive runs,
see BENCHMARKS.md). OLD_DPM renders "today's default" (its own defaults, no flags); NEW_DPM
renders the new default (no flags) and every CONFIG, a name and flags as NAME=FLAGS, each for
twice the old default's time (`--time`). Every run writes its relative MSE after each pass
(`--reference`, `--stats`); the table gives, per scene and run, the error when the old default
finished, the time it takes to reach the old default's error, and both as ratios to the old
default. Runs one at a time; nothing else should run on the machine.
"""

import json
import subprocess
import sys
from pathlib import Path


def render(dpm, scene, out, flags):
    stats = out.with_suffix(".json")
    cmd = [dpm, "render", str(scene), "-o", str(out), "--reference",
           str(scene.with_name(scene.stem + "-ref.pfm")), "--stats", str(stats)] + flags
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    passes = json.loads(stats.read_text())["per_pass"]
    return [(p["elapsed"], p["relative_mse"]) for p in passes]


def error_at(curve, t):
    """The error of the last pass finished by time t (the first pass's if none was)."""
    done = [e for (s, e) in curve if s <= t * 1.0001]
    return done[-1] if done else curve[0][1]


def time_to(curve, target):
    for s, e in curve:
        if e <= target:
            return s
    return None


def main():
    if len(sys.argv) < 5:
        print(__doc__)
        sys.exit(2)
    folder, old, new = Path(sys.argv[1]), sys.argv[2], sys.argv[3]
    scenes = sys.argv[4].split(",")
    configs = [("new default", [])]
    for c in sys.argv[5:]:
        name, _, flags = c.partition("=")
        configs.append((name, flags.split()))
    print("| scene | run | passes | rel. MSE at old default's time | ÷ old | time to old default's error (s) | ÷ old |")
    print("|---|---|---|---|---|---|---|")
    for name in scenes:
        scene = folder / f"{name}.toml"
        base = render(old, scene, folder / f"{name}-old.pfm", [])
        t0, e0 = base[-1]
        print(f"| {name} | old default | {len(base)} | {e0:.5f} | 1 | {t0:.2f} | 1 |")
        for label, flags in configs:
            tag = label.replace(" ", "-")
            extra = [] if "--passes" in flags else ["--time", f"{2 * t0:.3f}"]
            curve = render(new, scene, folder / f"{name}-{tag}.pfm", flags + extra)
            e = error_at(curve, t0)
            t = time_to(curve, e0)
            ts = f"{t:.2f} | {t / t0:.2f}" if t is not None else "not reached | –"
            print(f"| {name} | {label} `{' '.join(flags)}` | {len(curve)} | {e:.5f} | {e / e0:.2f} | {ts} |",
                  flush=True)


if __name__ == "__main__":
    main()
