#!/usr/bin/env python3
"""Single-view scans made from a closed model, as a scanner standing at one place sees it: an
open sheet of the faces it sees, with ragged borders, and optionally holes and a scanner's noise
along the line of sight. Each is written as an OBJ with scenes/bunny.toml around it (the
Cornell box, the model on the floor), its model and finish replaced, diffuse and glossy, for
benches/objects.py.

    benches/open_scans.py [--model scenes/models/data/bunny.obj] [--view X Y Z] [-o DIR]
                          [--figure OUT.png]

Writes DIR/<kind>.obj and DIR/<kind>_<finish>.toml for the kinds `sheet` (the faces whose normal
n has n · v > 0.15, v the view direction normalised, in the model's own frame), `holes` (the
sheet less the faces within 24 random spheres of 4 % of the model's size) and `noisy` (the
sheet with each vertex moved along v by Gaussian noise of 0.4 % of the model's size), and the
finishes `diffuse` and `glossy` (Ward, specular 0.4, roughness 0.1, as the bunny scene's),
and each scene again as <kind>_<finish>_one.toml with `sides = "one"`: one-sided disks, as
lobelight drew open models before they got back sides. Seeded: the same files every run.

`--figure OUT.png` also renders the floor under the sheet (diffuse, 256², no tone curve: the
same exposure for all) with the path tracer at 1,024 samples and the renderer at its defaults,
one-sided (top row) and with back sides (bottom row), cropped, not enlarged, into one PNG
(needs Pillow; LOBELIGHT names the binary, else target/release/lobelight).
"""

import argparse
import math
import os
import random
import re

FACING = 0.15
HOLES = 24
HOLE_RADIUS = 0.04
NOISE = 0.004

# The scene the sheets stand in: the bunny's (scenes/bunny.toml), its model and finish replaced.
BASE_SCENE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "bunny.toml")

FINISHES = {
    "diffuse": "diffuse = [0.45, 0.4, 0.35]",
    "glossy": "diffuse = [0.45, 0.4, 0.35]\nspecular = 0.4\nroughness = 0.1",
}


def scene_text(base, kind, finish):
    """`base` (the bunny's scene) with the model `kind`.obj and the model material `finish`."""
    # The base's opening comment and its model's line (with its comment) are the bunny's.
    base = re.sub(r"\A(#[^\n]*\n)+", "", base)
    text, paths = re.subn(r"(?m)^path = .*$", f'path = "{kind}.obj"', base)
    text, tables = re.subn(r"(?ms)^\[materials\.model\]\n.*?\n\n",
                           f"[materials.model]\n{finish}\n\n", text)
    if (paths, tables) != (1, 1):
        raise SystemExit(f"open_scans.py: {BASE_SCENE} has no one model path and material")
    return f"# A single-view scan ({kind}): benches/open_scans.py, from scenes/bunny.toml.\n{text}"


def read_obj(path):
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            w = line.split()
            if not w:
                continue
            if w[0] == "v":
                verts.append([float(x) for x in w[1:4]])
            elif w[0] == "f":
                idx = [int(x.split("/")[0]) for x in w[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                faces.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))
    return verts, faces


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def unit(a):
    n = math.sqrt(dot(a, a))
    return [x / n for x in a] if n > 0 else a


def seen(verts, faces, view):
    """The faces whose normal faces `view` by more than FACING."""
    out = []
    for f in faces:
        a, b, c = (verts[i] for i in f)
        n = unit(cross(sub(b, a), sub(c, a)))
        if dot(n, view) > FACING:
            out.append(f)
    return out


def holed(verts, faces, size, rng):
    centres = [verts[f[rng.randrange(3)]] for f in rng.sample(faces, HOLES)]
    r2 = (HOLE_RADIUS * size) ** 2

    def kept(f):
        c = [sum(verts[i][k] for i in f) / 3 for k in range(3)]
        return all(dot(sub(c, h), sub(c, h)) > r2 for h in centres)

    return [f for f in faces if kept(f)]


def noisy(verts, view, size, rng):
    return [[v[k] + rng.gauss(0.0, NOISE * size) * view[k] for k in range(3)] for v in verts]


def write_obj(path, verts, faces):
    used = sorted({i for f in faces for i in f})
    index = {old: new + 1 for new, old in enumerate(used)}
    with open(path, "w") as f:
        f.write("# a single-view scan: benches/open_scans.py\n")
        for i in used:
            f.write("v {:.6f} {:.6f} {:.6f}\n".format(*verts[i]))
        for t in faces:
            f.write("f {} {} {}\n".format(*(index[i] for i in t)))
    return len(used), len(faces)


def figure(out, path):
    """The floor under the sheet: path tracer and renderer, one-sided and with back sides."""
    import subprocess
    from PIL import Image
    lobelight = os.environ.get("LOBELIGHT", "target/release/lobelight")
    size, crop = 256, (32, 136, 224, 248)
    tiles = []
    for scene in ("sheet_diffuse_one", "sheet_diffuse"):
        for method in (["--method", "path", "--spp", "1024"], []):
            png = os.path.join(out, f"{scene}_{'path' if method else 'lobes'}.png")
            subprocess.run([lobelight, "render", os.path.join(out, f"{scene}.toml"), "-o", png,
                            "--width", str(size), "--height", str(size), "--tonemap", "none",
                            *method], check=True, capture_output=True)
            tiles.append(Image.open(png).convert("RGB").crop(crop))
    w, h = crop[2] - crop[0], crop[3] - crop[1]
    sheet = Image.new("RGB", (2 * w + 4, 2 * h + 4), "white")
    for k, tile in enumerate(tiles):
        sheet.paste(tile, ((k % 2) * (w + 4), (k // 2) * (h + 4)))
    sheet.save(path)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--model", default="scenes/models/data/bunny.obj")
    p.add_argument("--view", type=float, nargs=3, default=[0.3, 0.2, 1.0])
    p.add_argument("-o", "--out", default="out/open_scans")
    p.add_argument("--figure", help="also render the floor under the sheet into this PNG")
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    verts, faces = read_obj(args.model)
    lo = [min(v[k] for v in verts) for k in range(3)]
    hi = [max(v[k] for v in verts) for k in range(3)]
    size = max(hi[k] - lo[k] for k in range(3))
    view = unit(args.view)
    rng = random.Random(1)
    sheet = seen(verts, faces, view)
    kinds = {
        "sheet": (verts, sheet),
        "holes": (verts, holed(verts, sheet, size, rng)),
        "noisy": (noisy(verts, view, size, rng), sheet),
    }
    with open(BASE_SCENE) as f:
        base = f.read()
    for kind, (v, f) in kinds.items():
        obj = os.path.join(args.out, f"{kind}.obj")
        n_verts, n_faces = write_obj(obj, v, f)
        for finish, desc in FINISHES.items():
            scene = os.path.join(args.out, f"{kind}_{finish}.toml")
            text = scene_text(base, kind, desc)
            with open(scene, "w") as s:
                s.write(text)
            one = text.replace(f'path = "{kind}.obj"', f'path = "{kind}.obj"\nsides = "one"')
            with open(os.path.join(args.out, f"{kind}_{finish}_one.toml"), "w") as s:
                s.write(one)
        print(f"{kind}: {n_verts} vertices, {n_faces} faces of {len(faces)} -> {obj}")
    if args.figure:
        figure(args.out, args.figure)


if __name__ == "__main__":
    main()
