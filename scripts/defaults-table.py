#!/usr/bin/env python3
"""Measures render settings against references, for choosing the defaults (BENCHMARKS.md,
"Whole scenes and the defaults").

    scripts/defaults-table.py [--repeat N] [--seed S] DIR OLD_DPM NEW_DPM SCENE[,SCENE...] [CONFIG ...]

DIR holds SCENE.toml and SCENE-ref.pfm for each scene (the references: long progressive runs,
see BENCHMARKS.md). OLD_DPM renders "today's default" (its own defaults, no flags); NEW_DPM
renders the new default (no flags) and every CONFIG, a name and flags as NAME=FLAGS, each for
twice the old default's time (`--time`). Every run writes its relative MSE after each pass
(`--reference`, `--stats`); the table gives, per scene and run, the error when the old default
finished, the time it takes to reach the old default's error, and both as ratios to the old
default.

Errors do not depend on the machine (same seed, same image), times do: with `--repeat N` every
run is made N times, in turn (old default, then each configuration, N rounds), and each pass's
completion time is the median of its N runs. `--seed S` renders every run, the old default's
too, with `--seed S` (default: each binary's default seed, 1), to see how far a ratio moves
with the random numbers. The time to the old default's error is
interpolated between the two passes that straddle it (linearly in log error), so that it does
not jump by a whole pass. Runs one at a time; nothing else should run on the machine.
"""

import json
import math
import statistics
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


def median_curve(curves):
    """Per pass, the median completion time over runs that reached it, and its error (the
    same in every run)."""
    passes = min(len(c) for c in curves)
    return [(statistics.median(c[i][0] for c in curves), curves[0][i][1]) for i in range(passes)]


def error_at(curve, t):
    """The error of the last pass finished by time t (the first pass's if none was)."""
    done = [e for (s, e) in curve if s <= t * 1.0001]
    return done[-1] if done else curve[0][1]


def time_to(curve, target):
    """When the error first reaches `target`, interpolated in log error between passes."""
    before = None
    for s, e in curve:
        if e <= target:
            if before is None or before[1] <= 0 or e <= 0:
                return s
            (s0, e0) = before
            f = (math.log(e0) - math.log(target)) / (math.log(e0) - math.log(e))
            return s0 + f * (s - s0)
        before = (s, e)
    return None


def main():
    args = sys.argv[1:]
    repeat, seed = 1, []
    while args[:1] in (["--repeat"], ["--seed"]):
        if args[0] == "--repeat":
            repeat = int(args[1])
        else:
            seed = ["--seed", args[1]]
        args = args[2:]
    if len(args) < 4:
        print(__doc__)
        sys.exit(2)
    folder, old, new = Path(args[0]), args[1], args[2]
    scenes = args[3].split(",")
    configs = [("new default", [])]
    for c in args[4:]:
        name, _, flags = c.partition("=")
        configs.append((name, flags.split()))
    print("| scene | run | passes | rel. MSE at old default's time | ÷ old | time to old default's error (s) | ÷ old |")
    print("|---|---|---|---|---|---|---|")
    for name in scenes:
        scene = folder / f"{name}.toml"
        runs = {label: [] for label, _ in configs}
        olds = []
        for _ in range(repeat):
            olds.append(render(old, scene, folder / f"{name}-old.pfm", seed))
            t0 = statistics.median(c[-1][0] for c in olds)
            for label, flags in configs:
                tag = label.replace(" ", "-")
                extra = [] if "--passes" in flags else ["--time", f"{2 * t0:.3f}"]
                runs[label].append(render(new, scene, folder / f"{name}-{tag}.pfm", seed + flags + extra))
        base = median_curve(olds)
        t0, e0 = base[-1]
        print(f"| {name} | old default | {len(base)} | {e0:.5f} | 1 | {t0:.2f} | 1 |")
        for label, flags in configs:
            curve = median_curve(runs[label])
            e = error_at(curve, t0)
            t = time_to(curve, e0)
            ts = f"{t:.2f} | {t / t0:.2f}" if t is not None else "not reached | –"
            print(f"| {name} | {label} `{' '.join(flags)}` | {len(curve)} | {e:.5f} | {e / e0:.2f} | {ts} |",
                  flush=True)


if __name__ == "__main__":
    main()
