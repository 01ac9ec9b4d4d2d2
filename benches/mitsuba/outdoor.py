#!/usr/bin/env python3
"""External check of outdoor light against Mitsuba 3 (docs/measurements.md, "Outdoor light: a
sky and the sun").

An outdoor scene lit by a sky map alone: a ground (a thin slab, closed, so that the sky below
the horizon stays below it), a ball and a block, under a latitude-longitude EXR written here (a
blue sky brightening towards the horizon, a small bright sun, a dim ground below the horizon),
turned about the up axis. Mitsuba path-traces its meshes and sphere under its `envmap` of the
same EXR turned the same way; lobelight renders its splats with the same map. Two scenes: all
diffuse, and the ball in lobelight's Ward BRDF (`ward.py`). Per object, as `cornell.py` does:
the renderer at its defaults and lobelight's path tracer against Mitsuba converged, each
object's mean by lobelight's object IDs, with the bounds of 1 % (path tracer) and 1.5 %
(renderer). The sky's pixels are no object's: the camera sees the map itself there.

Mitsuba filters the map bilinearly, lobelight reads the nearest texel: the map is smooth at its
texels' scale (its sun a Gaussian of 4°, eight texels across at 512 × 256), so the two are one
sky.

The scenes `sunsky` and `sunsky_glossy` light the same objects by the Hosek–Wilkie sky and a
sun instead: Mitsuba's `sunsky` emitter against lobelight's `sky` and `sun` lights. The two
skies are one model from one RGB dataset; Mitsuba's RGB radiance is the model's divided by its
CIE Y normalization (106.75026), which lobelight's `scale` takes. Mitsuba's sun is a
limb-darkened disk 0.5358° across; lobelight's is a uniform disk of that size whose irradiance
is Mitsuba's, integrated here over the disk from Mitsuba's own radiance. Below the horizon
Mitsuba's sky is black and lobelight's is the model's ground (albedo × its irradiance / π):
the ground albedo is 0 in both, which makes both black there. Usage:

    pip install mitsuba numpy
    cargo build --release
    python3 benches/mitsuba/outdoor.py --size 128 --spp 2048 -o outdoor-out

It prints one JSON object on stdout; images, the map and objects.md go to the output folder.
"""

import argparse
import json
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from cornell import BOUND_PATH, BOUND_RENDERER, lobelight, objects, start, table  # noqa: E402

# The sky's map: its size, the sun's elevation and azimuth (degrees, in the map's frame), its
# angular width (σ of a Gaussian, degrees) and peak radiance, and the turn about y.
MAP = {"width": 512, "height": 256, "sun_elevation": 35.0, "sun_azimuth": 120.0,
       "sun_sigma": 4.0, "sun_peak": 40.0, "rotation": 40.0}
CAMERA = {"eye": [0.0, 1.3, 3.6], "target": [0.0, 0.35, 0.0], "fov": 45.0}
GROUND = {"albedo": [0.45, 0.42, 0.38], "half": [2.5, 0.05, 2.5], "centre": [0.0, -0.05, 0.0]}
BALL = {"albedo": [0.7, 0.3, 0.25], "centre": [-0.55, 0.45, 0.0], "radius": 0.45}
BLOCK = {"albedo": [0.3, 0.5, 0.7], "half": 0.3, "rotate_y": 25.0, "centre": [0.6, 0.3, 0.3]}
GLOSSY = {"diffuse": 0.4, "specular": 0.25, "roughness": 0.12}
# The sun and sky of the `sunsky` scenes: the sun's elevation and azimuth (degrees, lobelight's
# sky frame: azimuth 0 along −z, 90 along +x), the model's turbidity and ground albedo, and the
# sun's angular diameter (Mitsuba's default aperture).
SUNSKY = {"sun_elevation": 40.0, "sun_azimuth": 150.0, "turbidity": 3.0, "albedo": 0.0,
          "aperture": 0.5358}
# Mitsuba's RGB sky is the Hosek–Wilkie RGB radiance times its CIE Y normalization.
CIE_Y_NORMALIZATION = 1.0 / 106.7502593994140625


def sky_map(np):
    """The map, rows from the top (θ = 0), in Mitsuba's frame: texel (u, v) looks along
    (sin θ sin φ, cos θ, −sin θ cos φ), φ = 2π u, θ = π v."""
    w, h = MAP["width"], MAP["height"]
    u = (np.arange(w) + 0.5) / w
    v = (np.arange(h) + 0.5) / h
    phi, theta = np.meshgrid(2 * np.pi * u, np.pi * v)
    d = np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], -1)
    up = np.clip(d[..., 1], 0.0, 1.0)[..., None]
    zenith, horizon = np.array([0.25, 0.45, 0.95]), np.array([0.95, 0.95, 1.0])
    sky = horizon + (zenith - horizon) * np.sqrt(up)
    ground = np.array([0.22, 0.2, 0.18]) * (0.5 + 0.5 * np.clip(-d[..., 1], 0, 1))[..., None]
    # A smooth step across the horizon (1.5° wide): no texel-sharp edge for the filters to part on.
    t = np.clip(d[..., 1] / math.sin(math.radians(1.5)) * 0.5 + 0.5, 0, 1)[..., None]
    t = t * t * (3 - 2 * t)
    radiance = ground + (sky - ground) * t
    e, a = math.radians(MAP["sun_elevation"]), math.radians(MAP["sun_azimuth"])
    sun = np.array([math.cos(e) * math.sin(a), math.sin(e), -math.cos(e) * math.cos(a)])
    angle = np.arccos(np.clip(d @ sun, -1, 1))
    glow = MAP["sun_peak"] * np.exp(-(angle / math.radians(MAP["sun_sigma"])) ** 2)
    radiance = radiance + glow[..., None] * np.array([1.0, 0.9, 0.75])
    return radiance.astype(np.float32)


def sun_direction():
    """The direction towards the sun, y up."""
    e, a = math.radians(SUNSKY["sun_elevation"]), math.radians(SUNSKY["sun_azimuth"])
    return [math.cos(e) * math.sin(a), math.sin(e), -math.cos(e) * math.cos(a)]


def sun_irradiance(mi, np):
    """Mitsuba's sun: the irradiance its disk gives a surface facing it, integrated over the
    disk from the emitter's own radiance (the sky turned off), in polar rings about the sun."""
    emitter = mi.load_dict({"type": "sunsky", "sun_direction": sun_direction(), "sky_scale": 0.0,
                            "turbidity": SUNSKY["turbidity"], "albedo": SUNSKY["albedo"],
                            "sun_aperture": SUNSKY["aperture"], "to_world": z_up(mi)})
    s = np.array(sun_direction())
    a = np.cross(s, [0.0, 0.0, 1.0])
    a /= np.linalg.norm(a)
    b = np.cross(s, a)
    # Rings out to 1.2 radii: the disk's edge falls between two rings of 2,400.
    rings, spokes = 2400, 96
    reach = 1.2 * math.radians(SUNSKY["aperture"]) / 2
    gamma = (np.arange(rings) + 0.5) / rings * reach
    phi = (np.arange(spokes) + 0.5) / spokes * 2 * math.pi
    g, p = np.meshgrid(gamma, phi)
    g, p = g.ravel(), p.ravel()
    d = (np.cos(g)[:, None] * s + (np.sin(g) * np.cos(p))[:, None] * a
         + (np.sin(g) * np.sin(p))[:, None] * b)
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(-d[:, 0], -d[:, 1], -d[:, 2])
    radiance = np.array(emitter.eval(si)).reshape(3, -1)
    weight = np.sin(g) * (reach / rings) * (2 * math.pi / spokes)
    return [float(c) for c in radiance @ weight]


def z_up(mi):
    """Mitsuba's sky has z up in its own frame: turned to y up."""
    return mi.ScalarTransform4f().rotate([1, 0, 0], -90)


def lights_toml(sunsky, sun_e):
    if not sunsky:
        return f"""[[light]]
type = "environment"
map = "sky.exr"
rotation = {MAP['rotation']}
"""
    k = SUNSKY
    toward = sun_direction()
    return f"""[[light]]
type = "sky"
sun_elevation = {k['sun_elevation']}
sun_azimuth = {k['sun_azimuth']}
turbidity = {k['turbidity']}
ground_albedo = {k['albedo']}
scale = {CIE_Y_NORMALIZATION!r}

[[light]]
type = "sun"
direction = {[-c for c in toward]}
irradiance = {sun_e}
angle = {k['aperture']}
"""


def scene_toml(glossy, size, lights):
    ball = "glossy" if glossy else "ball"
    g = GLOSSY
    return f"""# Written by benches/mitsuba/outdoor.py: the outdoor check's scene.
[camera]
eye = {CAMERA['eye']}
target = {CAMERA['target']}
fov = {CAMERA['fov']}
resolution = [{size}, {size}]

[materials.ground]
diffuse = {GROUND['albedo']}

[materials.ball]
diffuse = {BALL['albedo']}

[materials.glossy]
diffuse = {g['diffuse']}
specular = {g['specular']}
roughness = {g['roughness']}

[materials.block]
diffuse = {BLOCK['albedo']}

{lights}
[[object]]
shape = "box"
scale = {GROUND['half']}
translate = {GROUND['centre']}
material = "ground"
spacing = 0.03

[[object]]
shape = "sphere"
radius = {BALL['radius']}
translate = {BALL['centre']}
material = "{ball}"
spacing = 0.02

[[object]]
shape = "box"
scale = {BLOCK['half']}
rotate = [0.0, {BLOCK['rotate_y']}, 0.0]
translate = {BLOCK['centre']}
material = "block"
spacing = 0.02
"""


def mitsuba_scene(mi, glossy, sky, size, spp, max_depth):
    """`sky`: the map's path, or None for Mitsuba's own sun and sky."""
    T = mi.ScalarTransform4f

    def diffuse(c):
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": c}}

    ball_bsdf = diffuse(BALL["albedo"])
    if glossy:
        import ward
        g = GLOSSY
        ball_bsdf = {"type": ward.register([g["diffuse"]] * 3, [g["specular"]] * 3, g["roughness"])}
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth},
        "sensor": {
            "type": "perspective", "fov": CAMERA["fov"], "fov_axis": "x",
            "to_world": T().look_at(origin=CAMERA["eye"], target=CAMERA["target"], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "sky": {"type": "envmap", "filename": str(sky),
                "to_world": T().rotate([0, 1, 0], MAP["rotation"])} if sky else
               {"type": "sunsky", "sun_direction": sun_direction(), "to_world": z_up(mi),
                "turbidity": SUNSKY["turbidity"], "albedo": SUNSKY["albedo"],
                "sun_aperture": SUNSKY["aperture"]},
        "ground": {"type": "cube", "bsdf": diffuse(GROUND["albedo"]),
                   "to_world": T().translate(GROUND["centre"]) @ T().scale(GROUND["half"])},
        "ball": {"type": "sphere", "center": BALL["centre"], "radius": BALL["radius"],
                 "bsdf": ball_bsdf},
        "block": {"type": "cube", "bsdf": diffuse(BLOCK["albedo"]),
                  "to_world": T().translate(BLOCK["centre"]) @ T().rotate([0, 1, 0], BLOCK["rotate_y"])
                  @ T().scale(BLOCK["half"])},
    })


def check(mi, name, args, out, sky, sun_e):
    """One scene: `name` is diffuse or glossy, under the map, or sunsky or sunsky_glossy."""
    glossy, sunsky = name.endswith("glossy"), name.startswith("sunsky")
    sky = None if sunsky else sky
    scene = out / f"outdoor_{name}.toml"
    scene.write_text(scene_toml(glossy, args.size, lights_toml(sunsky, sun_e)))
    converged = out / f"mitsuba_{name}.exr"
    path = out / f"lobelight_{name}_path.exr"
    seconds = None
    if not (args.reuse_references and converged.exists() and path.exists()):
        start = time.perf_counter()
        image = mi.render(mitsuba_scene(mi, glossy, sky, args.size, args.spp, args.max_depth + 1),
                          spp=args.spp, seed=args.seed)
        mi.Bitmap(image).write(str(converged))
        seconds = time.perf_counter() - start
        print(f"{name}: Mitsuba {args.spp} spp in {seconds:.1f} s", file=sys.stderr)
        lobelight("render", scene, "-o", path, "--method", "path", "--spp", args.path_spp)
    ids = out / f"ids_{name}.png"
    ours = out / f"lobelight_{name}.exr"
    lobelight("render", scene, "-o", ours, "--object-ids", ids)
    lobelight("render", scene, "-o", ours.with_suffix(".png"))
    path_label = f"path tracer ({args.path_spp} spp)"
    rows = {"renderer (defaults)": objects(ours, converged, ids),
            path_label: objects(path, converged, ids)}
    bounds = {"renderer (defaults)": BOUND_RENDERER, path_label: BOUND_PATH}
    within = all(abs(b) <= bounds[label] for label, row in rows.items() for b in row.values())
    return {"scene": name, "mitsuba_spp": args.spp, "mitsuba_seconds": seconds,
            "objects": rows, "within_bounds": within, "table": table(rows, bounds)}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--size", type=int, default=128, help="image side in pixels")
    p.add_argument("--spp", type=int, default=2048, help="Mitsuba's converged samples per pixel")
    p.add_argument("--path-spp", type=int, default=1024,
                   help="samples per pixel of lobelight's own path tracer")
    p.add_argument("--scenes", default="diffuse,glossy,sunsky,sunsky_glossy",
                   help="which of diffuse, glossy (under the map), sunsky, sunsky_glossy")
    p.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--max-depth", type=int, default=8,
                   help="lobelight's path length; Mitsuba gets one more (its emitter vertex)")
    p.add_argument("--reuse-references", action="store_true",
                   help="keep the output folder's Mitsuba and path-traced images: the renderer "
                        "alone again")
    p.add_argument("-o", "--output", type=Path, default=Path("outdoor-out"))
    args = p.parse_args()
    mi = start(args.variant)
    try:
        import numpy as np
    except ImportError:
        sys.exit("numpy is missing: `pip install numpy`")
    out = args.output
    out.mkdir(parents=True, exist_ok=True)
    sky = out / "sky.exr"
    mi.Bitmap(sky_map(np)).write(str(sky))
    names = [n for n in args.scenes.split(",") if n]
    unknown = set(names) - {"diffuse", "glossy", "sunsky", "sunsky_glossy"}
    if unknown:
        sys.exit(f"unknown scenes {sorted(unknown)}: diffuse, glossy, sunsky, sunsky_glossy")
    sun_e = sun_irradiance(mi, np)
    print(f"Mitsuba's sun: irradiance {sun_e} facing it", file=sys.stderr)
    scenes = [check(mi, n, args, out, sky, sun_e) for n in names]
    (out / "objects.md").write_text("".join(
        f"`outdoor_{s['scene']}.toml`, Mitsuba at {s['mitsuba_spp']} samples:\n\n{s['table']}\n"
        for s in scenes))
    result = {"size": args.size, "map": MAP, "sunsky": SUNSKY, "sun_irradiance": sun_e,
              "mitsuba": {"spp": args.spp, "variant": args.variant},
              "scenes": [{k: v for k, v in s.items() if k != "table"} for s in scenes]}
    (out / "outdoor.json").write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
