#!/usr/bin/env python3
"""External check of lobelight's diffuse transport against Mitsuba 3 (docs/scenes.md).

Mitsuba path-traces its own Cornell box (meshes) with the geometry, materials, light and camera
that scenes/diffuse.toml gives lobelight (splats). Both images are linear EXR with a box pixel
filter and the same bounce cap, so they compare pixel for pixel:

- lobelight at each photon count against Mitsuba with many samples per pixel (converged);
- at equal time: Mitsuba with as many samples as fit in that lobelight run's wall time (bake
  and frame, process start to image written), against its own converged image.

Figures come from `lobelight compare --json` (relMSE, SMAPE, FLIP). Usage:

    pip install mitsuba            # the scalar_rgb variant needs nothing else
    cargo build --release
    python3 benches/mitsuba/cornell.py --size 256 --spp 1024 -o mitsuba-out

It prints one JSON object on stdout; images and figures go to the output folder, with
objects.md: each object's mean against Mitsuba's, for the renderer at its defaults and for
lobelight's path tracer (`--path-spp`), the table docs/measurements.md shows.
"""

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
LOBELIGHT = ROOT / "target" / "release" / "lobelight"
SCENE = ROOT / "scenes" / "diffuse.toml"


def mitsuba_scene(mi, size, spp, max_depth):
    """Mitsuba's Cornell box at `size`², box filter, paths of at most `max_depth` vertices."""
    scene = mi.cornell_box()
    scene["integrator"]["max_depth"] = max_depth
    film = scene["sensor"]["film"]
    film["width"] = film["height"] = size
    film["rfilter"] = {"type": "box"}
    scene["sensor"]["sampler"]["sample_count"] = spp
    return mi.load_dict(scene)


def render_mitsuba(mi, size, spp, max_depth, seed, path):
    scene = mitsuba_scene(mi, size, spp, max_depth)
    start = time.perf_counter()
    image = mi.render(scene, spp=spp, seed=seed)
    seconds = time.perf_counter() - start
    mi.Bitmap(image).write(str(path))
    return seconds


def lobelight(*args):
    out = subprocess.run([str(LOBELIGHT), *map(str, args)], capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(out.stderr.strip())
    return json.loads(out.stdout) if "--json" in args else None


def compare(a, b):
    d = lobelight("compare", a, b, "--json")
    return {k: d[k] for k in ("rel_mse", "smape", "flip", "mean_relative", "energy")}


def objects(ours, converged, ids):
    """Each object's mean against Mitsuba's (relative bias), by lobelight's object IDs."""
    d = lobelight("compare", ours, converged, "--objects", ids, "--json")
    return {o["name"]: o["bias"] for o in d["objects"]}


def table(rows):
    """A markdown table: one row per image, one column per object, bias in percent."""
    names = list(next(iter(rows.values())).keys())
    lines = ["| against Mitsuba | " + " | ".join(names) + " |",
             "| --- |" + " ---: |" * len(names)]
    for label, row in rows.items():
        lines.append(f"| {label} | " + " | ".join(f"{100 * row[n]:+.2f} %" for n in names) + " |")
    return "\n".join(lines) + "\n"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--size", type=int, default=256, help="image side in pixels")
    p.add_argument("--spp", type=int, default=1024, help="Mitsuba's converged samples per pixel")
    p.add_argument("--photons", default="1000000,4000000",
                   help="lobelight's photon counts, comma-separated: one render and one "
                        "equal-time Mitsuba image each")
    p.add_argument("--variant", default="scalar_rgb", help="Mitsuba variant (llvm_ad_rgb is faster)")
    p.add_argument("-o", "--output", type=Path, default=Path("mitsuba-out"))
    p.add_argument("--path-spp", type=int, default=512,
                   help="samples per pixel of lobelight's own path tracer in the per-object table")
    p.add_argument("--max-depth", type=int, default=8,
                   help="lobelight's photon path length (scene [bake] max_depth); Mitsuba gets one "
                        "more, as its depth counts the emitter vertex")
    args = p.parse_args()
    if not LOBELIGHT.exists():
        sys.exit(f"{LOBELIGHT} is missing: run `cargo build --release` first")
    try:
        import mitsuba as mi
    except ImportError:
        sys.exit("Mitsuba 3 is missing: `pip install mitsuba`")
    mi.set_variant(args.variant)
    out = args.output
    out.mkdir(parents=True, exist_ok=True)
    depth = args.max_depth + 1

    converged = out / "mitsuba_converged.exr"
    converged_seconds = render_mitsuba(mi, args.size, args.spp, depth, 0, converged)
    runs = []
    for photons in (int(n) for n in args.photons.split(",")):
        ours = out / f"lobelight_{photons}.exr"
        start = time.perf_counter()
        try:
            report = lobelight("render", SCENE, "-o", ours, "--width", args.size, "--height",
                               args.size, "--photons", photons, "--json")
        except RuntimeError as e:
            # A device limit (e.g. a software device's loop limit): say so and go on.
            runs.append({"photons": photons, "error": str(e)})
            continue
        ours_seconds = time.perf_counter() - start
        # Samples per pixel that fit in lobelight's time, from the converged run's rate.
        equal_spp = max(1, int(args.spp * ours_seconds / converged_seconds))
        equal = out / f"mitsuba_equal_time_{photons}.exr"
        equal_seconds = render_mitsuba(mi, args.size, equal_spp, depth, 1, equal)
        runs.append({
            "photons": photons,
            "lobelight": {
                "seconds": ours_seconds,
                "adapter": report["adapter"],
                "against_converged": compare(ours, converged),
            },
            "mitsuba_equal_time": {
                "spp": equal_spp,
                "seconds": equal_seconds,
                "against_converged": compare(equal, converged),
            },
        })

    # Per object: the renderer at its defaults and lobelight's path tracer against Mitsuba's
    # converged image, by the object IDs of lobelight's view (objects.md, in the output folder).
    ids = out / "ids.png"
    lobes = out / "lobelight_default.exr"
    path = out / "lobelight_path.exr"
    lobelight("render", SCENE, "-o", lobes, "--width", args.size, "--height", args.size,
              "--object-ids", ids)
    lobelight("render", SCENE, "-o", path, "--width", args.size, "--height", args.size,
              "--method", "path", "--spp", args.path_spp)
    per_object = {
        "renderer (defaults)": objects(lobes, converged, ids),
        f"path tracer ({args.path_spp} spp)": objects(path, converged, ids),
    }
    (out / "objects.md").write_text(table(per_object))

    result = {
        "size": args.size,
        "objects": per_object,
        "max_depth_lobelight": args.max_depth,
        "max_depth_mitsuba": depth,
        "mitsuba_converged": {"spp": args.spp, "seconds": converged_seconds, "variant": args.variant},
        "runs": runs,
    }
    (out / "mitsuba.json").write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
