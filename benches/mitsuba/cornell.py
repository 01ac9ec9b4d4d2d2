#!/usr/bin/env python3
"""External check of lobelight against Mitsuba 3 (docs/measurements.md, "External check").

Mitsuba path-traces its own Cornell box (meshes) with the geometry, materials, light and camera
that lobelight's box scenes give (splats): `scenes/diffuse.toml` as Mitsuba's `cornell_box()`
is, and `scenes/cornell.toml` with the tall block in lobelight's Ward BRDF (`ward.py`, a Python
BSDF plugin). Both images are linear EXR with a box pixel filter and the same bounce cap, so
they compare pixel for pixel and object by object:

- per object, for each scene: the renderer at its defaults and lobelight's path tracer
  (`--path-spp`) against Mitsuba converged (`--spp`), each object's mean by lobelight's object
  IDs (objects.md in the output folder: the table docs/measurements.md shows, with the bounds
  of 1 % for the path tracer and 1.5 % for the renderer);
- on `diffuse.toml`, lobelight at each photon count (`--photons`) against Mitsuba converged,
  and Mitsuba at equal time: as many samples as fit in that lobelight run's wall time (bake
  and frame, process start to image written), against its own converged image.

Figures come from `lobelight compare --json` (relMSE, SMAPE, FLIP, per-object bias). Usage:

    pip install mitsuba
    cargo build --release
    python3 benches/mitsuba/cornell.py --size 256 --spp 4096 -o mitsuba-out
    python3 benches/mitsuba/cornell.py --reuse-references --photons "" -o mitsuba-out  # the renderer again

The default variant, `llvm_ad_rgb`, needs an LLVM of version 16 or newer (Debian 12: `apt-get
install libllvm19`); the script finds one and sets DRJIT_LIBLLVM_PATH unless it is set. The
Ward plugin needs a JIT variant: in `scalar_rgb` Mitsuba calls Python once a sample. It prints
one JSON object on stdout; images and figures go to the output folder.
"""

import argparse
import glob
import json
import os
import re
import subprocess
import sys
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
LOBELIGHT = ROOT / "target" / "release" / "lobelight"
SCENES = {"diffuse": ROOT / "scenes" / "diffuse.toml", "cornell": ROOT / "scenes" / "cornell.toml"}
# The open scan: `diffuse.toml`'s walls and light with a single-view sheet of the bunny
# (`benches/open_scans.py`) standing on the floor, written into the output folder. In Mitsuba
# the sheet is its mesh with a two-sided diffuse BSDF: what lobelight's back sides make of an
# open model.
SHEET = {"fit": 1.1, "translate": [0.0, -1.0, 0.0], "albedo": [0.45, 0.4, 0.35]}
# The largest |bias| of an object's mean against Mitsuba's converged image that the check allows.
BOUND_PATH = 0.01
BOUND_RENDERER = 0.015


def find_llvm():
    """The newest libLLVM of version 16 or more (older ones cannot build Dr.Jit's kernels)."""
    found = []
    for path in glob.glob("/usr/lib/*/libLLVM*.so*") + glob.glob("/usr/lib/llvm-*/lib/libLLVM*.so*"):
        m = re.search(r"libLLVM-?(\d+)", path)
        if m and int(m.group(1)) >= 16:
            found.append((int(m.group(1)), path))
    return max(found)[1] if found else None


def start(variant):
    """Mitsuba in `variant`, once lobelight's binary is there and an LLVM for the JIT variants
    is found; a clear exit where either is missing."""
    if not LOBELIGHT.exists():
        sys.exit(f"{LOBELIGHT} is missing: run `cargo build --release` first")
    if variant.startswith("llvm") and "DRJIT_LIBLLVM_PATH" not in os.environ:
        llvm = find_llvm()
        if llvm is None:
            sys.exit("the llvm variants need LLVM 16 or newer (Debian 12: `apt-get install "
                     "libllvm19`), or pass --variant scalar_rgb")
        os.environ["DRJIT_LIBLLVM_PATH"] = llvm
    try:
        import mitsuba as mi
    except ImportError:
        sys.exit("Mitsuba 3 is missing: `pip install mitsuba`")
    mi.set_variant(variant)
    return mi


def mitsuba_scene(mi, name, size, spp, max_depth):
    """Mitsuba's Cornell box as scene `name` gives it, at `size`², box filter, paths of at most
    `max_depth` vertices."""
    scene = mi.cornell_box()
    scene["integrator"]["max_depth"] = max_depth
    film = scene["sensor"]["film"]
    film["width"] = film["height"] = size
    film["rfilter"] = {"type": "box"}
    scene["sensor"]["sampler"]["sample_count"] = spp
    if name == "sheet":
        del scene["small-box"], scene["large-box"]
        scene["sheet"] = {
            "type": "obj", "filename": str(SCENES["sheet"].with_suffix(".obj")),
            "to_world": sheet_to_world(mi, SCENES["sheet"].with_suffix(".obj")),
            "bsdf": {"type": "twosided", "bsdf": {
                "type": "diffuse", "reflectance": {"type": "rgb", "value": SHEET["albedo"]}}},
        }
    if name == "cornell":
        # The tall block in the scene file's glossy material, lobelight's Ward.
        import ward
        m = tomllib.loads(SCENES["cornell"].read_text())["materials"]["glossy"]
        specular = m["specular"] if isinstance(m["specular"], list) else [m["specular"]] * 3
        scene["large-box"]["bsdf"] = {"type": ward.register(m["diffuse"], specular, m["roughness"])}
    return mi.load_dict(scene)


def sheet_to_world(mi, obj):
    """Where lobelight puts the sheet: its vertices' bounding box `fit` long, its bottom face
    centred at the origin (`anchor = "bottom"`), then moved by `translate`."""
    vertices = [list(map(float, line.split()[1:4])) for line in open(obj) if line.startswith("v ")]
    lo = [min(v[k] for v in vertices) for k in range(3)]
    hi = [max(v[k] for v in vertices) for k in range(3)]
    scale = SHEET["fit"] / max(h - l for l, h in zip(lo, hi))
    anchor = [0.5 * (lo[0] + hi[0]), lo[1], 0.5 * (lo[2] + hi[2])]
    T = mi.ScalarTransform4f
    return T().translate(SHEET["translate"]) @ T().scale(scale) @ T().translate([-a for a in anchor])


def write_sheet_scene(out, obj=None):
    """The open scan's scene in `out`, with its sheet: `obj`, or the single-view sheet of the
    bunny (made by `benches/open_scans.py`)."""
    made = out / "open_scans"
    if obj is None and not (made / "sheet.obj").exists():
        subprocess.run([sys.executable, str(ROOT / "benches" / "open_scans.py"), "-o", str(made)],
                       check=True, stdout=subprocess.DEVNULL)
    walls = SCENES["diffuse"].read_text().split("[[object]]                     # small block")[0]
    scene = out / "sheet.toml"
    (out / "sheet.obj").write_bytes(Path(obj or made / "sheet.obj").read_bytes())
    scene.write_text(
        f"{walls}\n[materials.model]\ndiffuse = {SHEET['albedo']}\n\n[[object]]\n"
        f"shape = \"model\"\npath = \"sheet.obj\"\nmaterial = \"model\"\nfit = {SHEET['fit']}\n"
        f"anchor = \"bottom\"\ntranslate = {SHEET['translate']}\n")
    return scene


def shown(path):
    """`path` as the table names it: from the project's root where it lies under it."""
    return path.relative_to(ROOT) if path.is_relative_to(ROOT) else path


def render_mitsuba(mi, name, size, spp, max_depth, seed, path):
    scene = mitsuba_scene(mi, name, size, spp, max_depth)
    start = time.perf_counter()
    image = mi.render(scene, spp=spp, seed=seed)
    # The JIT variants evaluate lazily: the image is rendered when it is written.
    mi.Bitmap(image).write(str(path))
    return time.perf_counter() - start


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


def table(rows, bounds):
    """A markdown table: one row per image, one column per object (bias in percent), then the
    largest |bias| against the row's bound."""
    names = list(next(iter(rows.values())).keys())
    lines = ["| against Mitsuba | " + " | ".join(names) + " | largest | bound |",
             "| --- |" + " ---: |" * (len(names) + 2)]
    for label, row in rows.items():
        worst = max(abs(row[n]) for n in names)
        cells = " | ".join(f"{100 * row[n]:+.2f} %" for n in names)
        lines.append(f"| {label} | {cells} | {100 * worst:.2f} % | {100 * bounds[label]:.1f} % |")
    return "\n".join(lines) + "\n"


def per_object(mi, name, args, depth, out):
    """Scene `name`: Mitsuba converged, the renderer at its defaults and lobelight's path
    tracer, each object's mean against Mitsuba's."""
    scene = SCENES[name]
    converged = out / f"mitsuba_{name}.exr"
    path = out / f"lobelight_{name}_path.exr"
    # The references (Mitsuba converged, lobelight's path tracer) take most of the run; a change
    # to the renderer alone re-runs its row against them.
    reuse = args.reuse_references and converged.exists() and path.exists()
    seconds = None
    if not reuse:
        seconds = render_mitsuba(mi, name, args.size, args.spp, depth, args.seed, converged)
        print(f"{name}: Mitsuba {args.spp} spp in {seconds:.1f} s", file=sys.stderr)
    ids = out / f"ids_{name}.png"
    lobes = out / f"lobelight_{name}.exr"
    size = ("--width", args.size, "--height", args.size)
    lobelight("render", scene, "-o", lobes, *size, "--object-ids", ids)
    if not reuse:
        lobelight("render", scene, "-o", path, *size, "--method", "path", "--spp", args.path_spp)
    path_label = f"path tracer ({args.path_spp} spp)"
    rows = {
        "renderer (defaults)": objects(lobes, converged, ids),
        path_label: objects(path, converged, ids),
    }
    bounds = {"renderer (defaults)": BOUND_RENDERER, path_label: BOUND_PATH}
    within = all(abs(b) <= bounds[label] for label, row in rows.items() for b in row.values())
    return {"scene": name, "mitsuba_spp": args.spp, "mitsuba_seconds": seconds,
            "objects": rows, "within_bounds": within, "table": table(rows, bounds)}


def equal_time(mi, args, depth, out, converged_seconds):
    """`diffuse.toml` at each photon count against Mitsuba converged (`per_object`'s image,
    rendered in `converged_seconds`) and at equal time."""
    converged = out / "mitsuba_diffuse.exr"
    runs = []
    for photons in (int(n) for n in args.photons.split(",") if n):
        ours = out / f"lobelight_{photons}.exr"
        start = time.perf_counter()
        try:
            report = lobelight("render", SCENES["diffuse"], "-o", ours, "--width", args.size,
                               "--height", args.size, "--photons", photons, "--json")
        except RuntimeError as e:
            # A device limit (e.g. a software device's loop limit): say so and go on.
            runs.append({"photons": photons, "error": str(e)})
            continue
        ours_seconds = time.perf_counter() - start
        # Samples per pixel that fit in lobelight's time, from the converged run's rate.
        equal_spp = max(1, int(args.spp * ours_seconds / converged_seconds))
        equal = out / f"mitsuba_equal_time_{photons}.exr"
        equal_seconds = render_mitsuba(mi, "diffuse", args.size, equal_spp, depth,
                                       args.seed + 1, equal)
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
    return runs


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--size", type=int, default=256, help="image side in pixels")
    p.add_argument("--spp", type=int, default=4096, help="Mitsuba's converged samples per pixel")
    p.add_argument("--scenes", default="diffuse,cornell",
                   help="the box scenes of the per-object table, comma-separated (and `sheet`: "
                        "an open scan in the diffuse box)")
    p.add_argument("--photons", default="1000000,4000000",
                   help="lobelight's photon counts on diffuse.toml, comma-separated: one render "
                        "and one equal-time Mitsuba image each (empty: none)")
    p.add_argument("--sheet", type=Path,
                   help="the `sheet` scene's model (OBJ; default: the bunny's single-view sheet)")
    p.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant")
    p.add_argument("-o", "--output", type=Path, default=Path("mitsuba-out"))
    p.add_argument("--path-spp", type=int, default=2048,
                   help="samples per pixel of lobelight's own path tracer in the per-object table")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of Mitsuba's converged images (a second seed gives benches/noise.py "
                        "the reference's own noise); the equal-time images take the next")
    p.add_argument("--reuse-references", action="store_true",
                   help="keep the output folder's Mitsuba converged and path-traced images where "
                        "both are there (same --size, --spp and --path-spp): only the renderer's "
                        "rows are rendered again, and no equal-time runs")
    p.add_argument("--max-depth", type=int, default=8,
                   help="lobelight's photon path length (scene [bake] max_depth); Mitsuba gets one "
                        "more, as its depth counts the emitter vertex")
    args = p.parse_args()
    names = [n for n in args.scenes.split(",") if n]
    unknown = [n for n in names if n not in SCENES and n != "sheet"]
    if unknown:
        sys.exit(f"unknown scene {unknown[0]!r}: the check knows {', '.join(SCENES)}")
    mi = start(args.variant)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    out = args.output
    out.mkdir(parents=True, exist_ok=True)
    if "sheet" in names:
        SCENES["sheet"] = write_sheet_scene(out, args.sheet)
    depth = args.max_depth + 1

    scenes = [per_object(mi, name, args, depth, out) for name in names]
    (out / "objects.md").write_text("".join(
        f"`{shown(SCENES[s['scene']])}`, Mitsuba at {s['mitsuba_spp']} samples:\n\n{s['table']}\n"
        for s in scenes))
    diffuse = [s for s in scenes if s["scene"] == "diffuse"]
    runs = []
    if args.photons and diffuse and diffuse[0]["mitsuba_seconds"] is not None:
        runs = equal_time(mi, args, depth, out, diffuse[0]["mitsuba_seconds"])

    result = {
        "size": args.size,
        "scenes": [{k: v for k, v in s.items() if k != "table"} for s in scenes],
        "max_depth_lobelight": args.max_depth,
        "max_depth_mitsuba": depth,
        "mitsuba": {"spp": args.spp, "variant": args.variant},
        "runs": runs,
    }
    (out / "mitsuba.json").write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
