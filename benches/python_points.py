#!/usr/bin/env python3
"""A million points handed to lobelight as numpy arrays against the same points read from a
PLY file by the command (docs/measurements.md, "From Python: points as arrays").

The points lie on a ball (a Fibonacci sphere, with their normals) standing on a ground, lit by
the sun; the same scene otherwise. Each round runs, in turn, the command on the file (process
start to image written) and the package on the arrays (scene built from them, bake, image in
hand), both on the CPU mirror; it prints each run's seconds, the medians and their ratio as
one JSON object. Usage (after `pip install ./python` and `cargo build --release`):

    python3 benches/python_points.py --points 1000000 --rounds 3
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import lobelight

ROOT = Path(__file__).resolve().parents[1]
COMMAND = ROOT / "target" / "release" / "lobelight"

CAMERA = {"eye": [0.0, 1.2, 4.0], "target": [0.0, 0.8, 0.0], "fov": 45.0,
          "resolution": [256, 256]}
LIGHT = {"type": "sun", "direction": [-0.5, -0.7, -0.5], "irradiance": [3.0, 3.0, 3.0]}
GROUND = {"shape": "quad", "size": [6.0, 6.0], "rotate": [-90.0, 0.0, 0.0], "spacing": 0.05,
          "material": "ground"}
MATERIALS = {"ball": {"diffuse": [0.7, 0.6, 0.5]}, "ground": {"diffuse": [0.4, 0.4, 0.4]}}
BAKE = {"photons": 500000}


def ball(n):
    """n points evenly on a unit ball resting on y = 0, and their normals (float32)."""
    k = np.arange(n, dtype=np.float64) + 0.5
    phi = np.arccos(1 - 2 * k / n)
    theta = np.pi * (1 + 5 ** 0.5) * k
    normals = np.stack([np.cos(theta) * np.sin(phi), np.cos(phi), np.sin(theta) * np.sin(phi)], 1)
    return (normals + [0.0, 1.0, 0.0]).astype(np.float32), normals.astype(np.float32)


def write_ply(path, points, normals):
    """A binary little-endian PLY of points with normals."""
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"element vertex {len(points)}\n"
              "property float x\nproperty float y\nproperty float z\n"
              "property float nx\nproperty float ny\nproperty float nz\nend_header\n")
    with open(path, "wb") as f:
        f.write(header.encode())
        np.concatenate([points, normals], 1).astype("<f4").tofile(f)


def scene_toml():
    """The scene file: the same tables as `lobelight.build` gets, the ball from ball.ply."""
    def table(d):
        return "".join(f"{k} = {json.dumps(v)}\n" for k, v in d.items())
    return ("[camera]\n" + table(CAMERA) + "\n[bake]\n" + table(BAKE)
            + "".join(f"\n[materials.{name}]\n" + table(m) for name, m in MATERIALS.items())
            + "\n[[light]]\n" + table(LIGHT)
            + "\n[[object]]\n" + table(GROUND)
            + '\n[[object]]\nshape = "model"\npath = "ball.ply"\nmaterial = "ball"\n')


def by_command(scene, out):
    t = time.perf_counter()
    done = subprocess.run([str(COMMAND), "render", str(scene), "-o", str(out), "--cpu"],
                          capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(done.stderr)
    return time.perf_counter() - t


def by_arrays(points, normals):
    t = time.perf_counter()
    scene = lobelight.build([GROUND, lobelight.points(points, normals=normals, material="ball")],
                            lights=[LIGHT], camera=CAMERA, materials=MATERIALS, bake=BAKE)
    image = lobelight.Renderer(scene, engine="cpu").render()
    seconds = time.perf_counter() - t
    assert image.shape == (256, 256, 3) and np.isfinite(image).all()
    return seconds


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--points", type=int, default=1_000_000)
    p.add_argument("--rounds", type=int, default=3)
    args = p.parse_args()
    if not COMMAND.exists():
        sys.exit(f"{COMMAND} is missing: run `cargo build --release` first")
    points, normals = ball(args.points)
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        write_ply(d / "ball.ply", points, normals)
        (d / "scene.toml").write_text(scene_toml())
        command, arrays = [], []
        for _ in range(args.rounds):
            command.append(by_command(d / "scene.toml", d / "out.exr"))
            arrays.append(by_arrays(points, normals))
            print(f"command {command[-1]:.2f} s, arrays {arrays[-1]:.2f} s", file=sys.stderr)
    result = {"points": args.points, "command_s": command, "arrays_s": arrays,
              "command_median_s": statistics.median(command),
              "arrays_median_s": statistics.median(arrays),
              "ratio": statistics.median(arrays) / statistics.median(command)}
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
