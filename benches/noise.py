#!/usr/bin/env python3
"""The renderer's noise and error per object against a converged image, the reference's own
noise taken out: the measure of the photon map's blotches (issue "smooth diffuse light").

    benches/noise.py [--size 256] [--seeds 6] [--reference A.exr B.exr | --reference-spp 2048]
                     [-o DIR] SCENE [-- RENDER_ARGS...]

A blotch is noise of the bake: it changes with the photons' seed. So the renderer runs at its
defaults (plus RENDER_ARGS, e.g. `--photons 6000000` or `--radius 0.075`) with seeds 1..N, and
per object:

- noise: the relMSE of one image against the mean of all seeds, estimated as half the relMSE
  between images of two seeds, averaged over the pairs (1, 2), (3, 4), …;
- against the reference: the relMSE of each image against reference A, averaged over seeds;
- the reference's own noise: half the relMSE between A and B, two converged images of other
  seeds (lobelight's path tracer at `--reference-spp` with seeds 1 and 2 unless given);
- error: against the reference less the reference's own noise, the relMSE the renderer would
  have against a noiseless reference (noise and bias together).

relMSE is `lobelight compare`'s, per object by the object IDs of the first seed's image. Writes
DIR/noise.md (the table) and DIR/noise.json, and prints the table. Needs a built
`target/release/lobelight` (or LOBELIGHT=path).
"""

import argparse
import json
import os
import subprocess
import sys
import time


def run(lobelight, args):
    out = subprocess.run([lobelight, *map(str, args)], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"noise.py: lobelight {' '.join(map(str, args))}: {out.stderr.strip()}")
    return out.stdout


def objects(lobelight, a, b, ids):
    """Per object (name → figures) of image a against image b."""
    report = json.loads(run(lobelight, ["compare", a, b, "--objects", ids, "--json"]))
    return {o["name"]: o for o in report["objects"]}


def mean(values):
    values = list(values)
    return sum(values) / len(values)


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        at = argv.index("--")
        argv, extra = argv[:at], argv[at + 1:]
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene")
    p.add_argument("--size", type=int, default=256)
    p.add_argument("--seeds", type=int, default=6, help="renderer images, one a seed (even, ≥ 2)")
    p.add_argument("--reference", nargs=2, metavar=("A", "B"),
                   help="two converged images of the scene, independent of each other")
    p.add_argument("--reference-spp", type=int, default=2048,
                   help="samples of lobelight's path tracer for the references, when not given")
    p.add_argument("-o", "--output", default="noise")
    a = p.parse_args(argv)
    if a.seeds < 2 or a.seeds % 2:
        sys.exit("noise.py: --seeds must be even and at least 2 (the noise comes from pairs)")
    lobelight = os.environ.get("LOBELIGHT", "target/release/lobelight")
    os.makedirs(a.output, exist_ok=True)
    dims = ["--width", a.size, "--height", a.size]
    ids = os.path.join(a.output, "ids.png")

    start = time.time()
    images = []
    for seed in range(1, a.seeds + 1):
        image = os.path.join(a.output, f"renderer_{seed}.exr")
        more = ["--object-ids", ids] if seed == 1 else []
        run(lobelight, ["render", a.scene, "-o", image, "--seed", seed, *dims, *more, *extra])
        images.append(image)
    seconds = (time.time() - start) / a.seeds
    if a.reference:
        ref_a, ref_b = a.reference
    else:
        ref_a, ref_b = (os.path.join(a.output, f"path_{s}.exr") for s in (1, 2))
        for seed, image in ((1, ref_a), (2, ref_b)):
            if not os.path.exists(image):
                run(lobelight, ["render", a.scene, "-o", image, "--method", "path", "--spp",
                                a.reference_spp, "--seed", seed, *dims])

    pairs = [objects(lobelight, images[i], images[i + 1], ids) for i in range(0, a.seeds, 2)]
    against = [objects(lobelight, image, ref_a, ids) for image in images]
    reference = objects(lobelight, ref_a, ref_b, ids)
    rows = []
    for name in against[0]:
        noise = mean(p[name]["rel_mse"] / 2 for p in pairs)
        vs_ref = mean(x[name]["rel_mse"] for x in against)
        ref_noise = reference[name]["rel_mse"] / 2
        rows.append({
            "object": name,
            "pixels": against[0][name]["pixels"],
            "noise": noise,
            "against_reference": vs_ref,
            "reference_noise": ref_noise,
            "error": vs_ref - ref_noise,
            "bias": mean(x[name]["bias"] for x in against),
        })
    lines = [f"`{a.scene}` {' '.join(extra)} ({a.size}², {a.seeds} seeds, "
             f"{seconds:.1f} s an image)", "",
             "| object | pixels | noise | against the reference | the reference's noise | "
             "error | mean's bias |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in rows:
        lines.append(f"| {r['object']} | {r['pixels']} | {r['noise']:.5f} | "
                     f"{r['against_reference']:.5f} | {r['reference_noise']:.5f} | "
                     f"{r['error']:.5f} | {100 * r['bias']:+.2f} % |")
    md = "\n".join(lines) + "\n"
    with open(os.path.join(a.output, "noise.md"), "w") as f:
        f.write(md)
    with open(os.path.join(a.output, "noise.json"), "w") as f:
        json.dump({"scene": a.scene, "size": a.size, "seeds": a.seeds, "render_args": extra,
                   "seconds_an_image": seconds, "references": [ref_a, ref_b], "rows": rows},
                  f, indent=1)
    print(md)


if __name__ == "__main__":
    main()
