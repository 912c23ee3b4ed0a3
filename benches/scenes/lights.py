#!/usr/bin/env python3
"""Writes the many-lights and open-floor benchmarks (BENCHMARKS.md, "Many lights" and "Open
skies"): a matte floor, a glass ball and a matte ball under N point lights of the same total
power, spread on a grid 4 units above the floor, the sky open (black) around them.

    benches/scenes/lights.py OUT_DIR [N ...]   (default 1 16 256 4096)

Writes OUT_DIR/lights-N.pbrt for each N (pbrt-v3's language, 320x240; dpm and pbrt-v3 both
render it): `dpm render OUT_DIR/lights-1.pbrt --passes 2`. lights-1 is the open floor.
"""

import math
import os
import sys


def scene(n):
    side = math.ceil(math.sqrt(n))
    power = 60.0 / n
    lights = []
    for i in range(n):
        # Spread over a 6 x 6 square, centred, whatever n.
        x = -3.0 + 6.0 * ((i % side) + 0.5) / side
        z = -3.0 + 6.0 * ((i // side) + 0.5) / side
        lights.append(
            f'LightSource "point" "point from" [{x:.4f} 4 {z:.4f}] "rgb I" [{power:.6g} {power:.6g} {power:.6g}]'
        )
    return "\n".join(
        [
            'LookAt 0 3 7  0 0.5 0  0 1 0',
            'Camera "perspective" "float fov" [45]',
            'Film "image" "integer xresolution" [320] "integer yresolution" [240] "string filename" "lights.exr"',
            'Sampler "random" "integer pixelsamples" [16]',
            'Integrator "path" "integer maxdepth" [5]',
            "WorldBegin",
            *lights,
            'AttributeBegin',
            '  Material "matte" "rgb Kd" [0.5 0.5 0.5]',
            '  Shape "trianglemesh" "point P" [-5 0 -5  5 0 -5  5 0 5  -5 0 5] "integer indices" [0 2 1 0 3 2]',
            "AttributeEnd",
            'AttributeBegin',
            '  Material "glass" "float index" [1.5]',
            '  Translate -0.8 0.7 0',
            '  Shape "sphere" "float radius" [0.7]',
            "AttributeEnd",
            'AttributeBegin',
            '  Material "matte" "rgb Kd" [0.7 0.3 0.2]',
            '  Translate 0.9 0.6 0.3',
            '  Shape "sphere" "float radius" [0.6]',
            "AttributeEnd",
            "WorldEnd",
            "",
        ]
    )


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    counts = [int(a) for a in sys.argv[2:]] or [1, 16, 256, 4096]
    os.makedirs(out, exist_ok=True)
    for n in counts:
        path = os.path.join(out, f"lights-{n}.pbrt")
        with open(path + ".part", "w") as f:
            f.write(scene(n))
        os.replace(path + ".part", path)
        print(path)


if __name__ == "__main__":
    main()
