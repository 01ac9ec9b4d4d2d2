#!/usr/bin/env python3
"""A point cloud from numpy, lit by a sky and the sun, rendered to a PNG and an EXR.

    pip install ./python
    python3 examples/points.py [--size 256] [-o points]
"""

import argparse

import numpy as np

import lobelight

p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
p.add_argument("--size", type=int, default=256, help="image side in pixels")
p.add_argument("-o", "--output", default="points", help="writes OUTPUT.png and OUTPUT.exr")
args = p.parse_args()

# 200,000 points on a bumpy ball, with their colours: what a scan hands over.
rng = np.random.default_rng(7)
d = rng.normal(size=(200_000, 3))
d /= np.linalg.norm(d, axis=1, keepdims=True)
bumps = 1.0 + 0.05 * np.sin(8 * d[:, 0]) * np.sin(8 * d[:, 2])
xyz = d * bumps[:, None]
colors = np.stack([0.5 + 0.4 * d[:, 0], 0.5 + 0.2 * d[:, 1], 0.6 - 0.3 * d[:, 2]], 1)

scene = lobelight.build(
    [lobelight.points(xyz, colors=colors, fit=1.0, anchor="bottom"),
     {"shape": "quad", "size": [6, 6], "rotate": [-90, 0, 0], "spacing": 0.05,
      "material": "ground"}],
    lights=[{"type": "sky", "sun_elevation": 35, "sun_azimuth": 130, "scale": 0.05},
            {"type": "sun", "direction": [-0.63, -0.57, -0.53], "irradiance": [9, 8.4, 7.5]}],
    camera={"eye": [0, 0.7, 2.6], "target": [0, 0.4, 0], "fov": 50,
            "resolution": [args.size, args.size]},
    materials={"ground": {"diffuse": [0.45, 0.4, 0.33]}},
    bake={"photons": 300_000})

renderer = lobelight.Renderer(scene)
image = renderer.render()                       # linear HDR, float32
lobelight.save(f"{args.output}.exr", image)
lobelight.save(f"{args.output}.png", renderer.tone_map())
print(f"{scene}: {args.output}.png and .exr on {renderer.adapter}")
