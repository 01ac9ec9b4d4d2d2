#!/usr/bin/env python3
"""Every object of each scene against the path tracer of the same splats, direct and indirect
light apart: one command writes the table that docs/measurements.md shows.

    benches/objects.py [--size 64] [--direct-spp 256] [--indirect-spp 2048] [--frames N]
                       [--reuse-references] [-o DIR] SCENE...

For each scene: the path tracer's direct and indirect images (with the object IDs), the
renderer's at its default settings (one bake, cached, for both; `--frames N` refinement frames
in place of the default 16), and `lobelight compare
--objects` of each pair. Writes DIR/objects.md (a row per object: its pixels and its mean's
bias in direct, in indirect and in all light, and the largest |bias| of the scene) and
DIR/objects.json, and prints the table. The engine is the one `render` picks (the CPU mirror
beside a software rasterizer). Needs a built `target/release/lobelight` (or LOBELIGHT=path).
"""

import argparse
import json
import os
import subprocess
import sys
import time

# Objects smaller than this many pixels are listed but not counted in the scene's largest bias:
# their means carry the path tracer's noise more than the renderer's error.
MIN_PIXELS = 32


def run(lobelight, args):
    out = subprocess.run([lobelight, *args], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"objects.py: lobelight {' '.join(args)}: {out.stderr.strip()}")
    return out.stdout


def measure(lobelight, scene, size, spp, out, frames=None, reuse=False):
    name = os.path.splitext(os.path.basename(scene))[0]
    base = os.path.join(out, name)
    dims = ["--width", str(size), "--height", str(size)]
    ids = f"{base}_ids.png"
    cache = f"{base}.bake"
    if os.path.exists(cache):
        os.remove(cache)
    t = time.time()
    biases = {}
    for light in ("direct", "indirect"):
        pt = f"{base}_path_{light}.exr"
        if not (reuse and os.path.exists(pt) and os.path.exists(ids)):
            run(lobelight, ["render", scene, "-o", pt, "--method", "path", "--spp",
                            str(spp[light]), "--show", light, "--object-ids", ids, *dims])
        lobes = f"{base}_lobes_{light}.exr"
        more = ["--spp", str(frames)] if frames else []
        run(lobelight, ["render", scene, "-o", lobes, "--show", light, "--cache", cache, *dims,
                        *more])
        report = json.loads(run(lobelight, ["compare", lobes, pt, "--objects", ids, "--json"]))
        biases[light] = {o["name"]: o for o in report["objects"]}
    rows = []
    for obj, d in biases["direct"].items():
        i = biases["indirect"].get(obj, {})
        # All light: the two terms' means summed, against the path tracer's.
        both = i and d["reference_mean"] + i["reference_mean"]
        rows.append({
            "object": obj,
            "pixels": d["pixels"],
            "direct_bias": d["bias"],
            "indirect_bias": i.get("bias"),
            "all_bias": (d["mean"] + i["mean"]) / both - 1 if both else None,
        })
    counted = [r for r in rows if r["pixels"] >= MIN_PIXELS]
    worst = max((abs(b) for r in counted for b in (r["direct_bias"], r["indirect_bias"])
                 if b is not None), default=0.0)
    worst_all = max((abs(r["all_bias"]) for r in counted if r["all_bias"] is not None),
                    default=0.0)
    return {"scene": scene, "size": size, "spp": spp, "frames": frames or 16,
            "seconds": time.time() - t,
            "rows": rows, "largest_bias": worst, "largest_all_bias": worst_all}


def percent(b):
    return "" if b is None else f"{100 * b:+.2f} %"


def table(results):
    lines = ["| scene | object | pixels | direct | indirect | all light |",
             "| --- | --- | ---: | ---: | ---: | ---: |"]
    for r in results:
        name = os.path.splitext(os.path.basename(r["scene"]))[0]
        for row in r["rows"]:
            lines.append(f"| {name} | {row['object']} | {row['pixels']} | "
                         f"{percent(row['direct_bias'])} | {percent(row['indirect_bias'])} | "
                         f"{percent(row['all_bias'])} |")
        lines.append(f"| {name} | **largest \\|bias\\| (objects of {MIN_PIXELS}+ pixels; "
                     f"{r['frames']} frames)** | | **{100 * r['largest_bias']:.2f} %** | | "
                     f"**{100 * r['largest_all_bias']:.2f} %** |")
    return "\n".join(lines) + "\n"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scenes", nargs="+")
    p.add_argument("--size", type=int, default=64)
    p.add_argument("--direct-spp", type=int, default=256)
    p.add_argument("--indirect-spp", type=int, default=2048)
    p.add_argument("--frames", type=int, help="the renderer's refinement frames (default 16)")
    p.add_argument("--reuse-references", action="store_true",
                   help="keep the path-traced images already in the output folder")
    p.add_argument("-o", "--output", default="objects")
    a = p.parse_args()
    lobelight = os.environ.get("LOBELIGHT", "target/release/lobelight")
    os.makedirs(a.output, exist_ok=True)
    spp = {"direct": a.direct_spp, "indirect": a.indirect_spp}
    results = []
    for scene in a.scenes:
        print(f"objects.py: {scene}", file=sys.stderr)
        results.append(measure(lobelight, scene, a.size, spp, a.output, a.frames,
                               a.reuse_references))
        # Written after each scene, so that a long run keeps what it measured.
        md = table(results)
        with open(os.path.join(a.output, "objects.md"), "w") as f:
            f.write(md)
        with open(os.path.join(a.output, "objects.json"), "w") as f:
            json.dump(results, f, indent=1)
    print(md)


if __name__ == "__main__":
    main()
