"""The Python package against the command: the same scene gives the same pixels through either,
arrays give what the same points in a file give, and bad input raises the command's message.

Run by python/test.sh after `cargo test --release`, which builds the command these tests run
(target/release/lobelight, or $LOBELIGHT).
"""

import os
import struct
import subprocess
import sys
import tempfile
import threading
import unittest
import zlib
from pathlib import Path

import numpy as np

import lobelight

ROOT = Path(__file__).resolve().parents[2]
COMMAND = Path(os.environ.get("LOBELIGHT", ROOT / "target" / "release" / "lobelight"))

# A small lit room: a Cornell box with a glossy ball and an area light, few photons, 40².
BOX = """
[camera]
eye = [0.0, 0.0, 3.9]
target = [0.0, 0.0, 0.0]
fov = 39.3
resolution = [40, 40]

[bake]
photons = 60000

[materials.white]
diffuse = [0.8, 0.8, 0.8]

[materials.red]
diffuse = [0.6, 0.05, 0.05]

[materials.glossy]
diffuse = [0.2, 0.2, 0.3]
specular = 0.4
roughness = 0.15

[[light]]
type = "area"
center = [0.0, 0.99, 0.0]
size = [0.5, 0.5]
normal = [0.0, -1.0, 0.0]
u_axis = [1.0, 0.0, 0.0]
radiance = [12.0, 12.0, 12.0]

[[object]]
shape = "cornell_box"
material = "white"
left_material = "red"
right_material = "white"
spacing = 0.08

[[object]]
shape = "sphere"
radius = 0.35
translate = [0.0, -0.65, 0.0]
material = "glossy"
spacing = 0.05
"""


def read_png(path):
    """An 8-bit RGB or RGBA PNG (not interlaced) as height × width × channels, with zlib alone."""
    data = Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, header = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    assert depth == 8 and interlace == 0 and colour in (2, 6), header
    channels = 3 if colour == 2 else 4
    raw = zlib.decompress(idat)
    stride = width * channels
    rows = np.zeros((height, stride), np.int32)
    prev = np.zeros(stride, np.int32)
    for y in range(height):
        line = raw[y * (stride + 1):(y + 1) * (stride + 1)]
        kind, row = line[0], np.frombuffer(line[1:], np.uint8).astype(np.int32)
        out = np.zeros(stride, np.int32)
        for x in range(stride):
            a = out[x - channels] if x >= channels else 0
            b = prev[x]
            c = prev[x - channels] if x >= channels else 0
            if kind == 0:
                p = 0
            elif kind == 1:
                p = a
            elif kind == 2:
                p = b
            elif kind == 3:
                p = (a + b) // 2
            else:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            out[x] = (row[x] + p) & 0xFF
        rows[y] = out
        prev = out
    return rows.reshape(height, width, channels).astype(np.uint8)


def command(*args):
    if not COMMAND.exists():
        raise unittest.SkipTest(f"{COMMAND} is missing: run `cargo build --release` first")
    return subprocess.run([str(COMMAND), *map(str, args)], capture_output=True, text=True)


def ball_points(n=4000, radius=0.3, centre=(0.0, -0.7, 0.0)):
    """Points evenly on a ball (a Fibonacci sphere) with their outward normals."""
    k = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * k / n)
    theta = np.pi * (1 + 5 ** 0.5) * k
    normals = np.stack([np.cos(theta) * np.sin(phi), np.cos(phi), np.sin(theta) * np.sin(phi)], 1)
    return (np.asarray(centre) + radius * normals).astype(np.float32), normals.astype(np.float32)


def write_ply(path, pts, normals):
    lines = ["ply", "format ascii 1.0", f"element vertex {len(pts)}", "property float x",
             "property float y", "property float z", "property float nx", "property float ny",
             "property float nz", "end_header"]
    lines += [" ".join(repr(float(v)) for v in (*p, *n)) for p, n in zip(pts, normals)]
    Path(path).write_text("\n".join(lines) + "\n")


class SceneFromFile(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.TemporaryDirectory()
        cls.path = Path(cls.dir.name) / "box.toml"
        cls.path.write_text(BOX)
        cls.scene = lobelight.load(cls.path)
        cls.renderer = lobelight.Renderer(cls.scene, engine="cpu")
        cls.image = cls.renderer.render()

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    def test_the_image_is_linear_float32_of_the_camera_s_size(self):
        self.assertEqual(self.scene.resolution, (40, 40))
        self.assertEqual(self.image.shape, (40, 40, 3))
        self.assertEqual(self.image.dtype, np.float32)
        self.assertTrue(np.isfinite(self.image).all())
        self.assertGreater(float(self.image.mean()), 0.01)
        self.assertEqual(self.renderer.engine, "cpu")

    def test_the_tone_map_is_the_command_s_png_byte_for_byte(self):
        png = Path(self.dir.name) / "box.png"
        done = command("render", self.path, "-o", png, "--cpu")
        self.assertEqual(done.returncode, 0, done.stderr)
        theirs = read_png(png)[..., :3]
        # The scene's view again (other tests draw other views and the path tracer's image):
        # the same pixels, tone-mapped as the command's PNG.
        image = self.renderer.render()
        np.testing.assert_array_equal(image, self.image)
        ours = self.renderer.tone_map()
        self.assertEqual(ours.shape, (40, 40, 3))
        self.assertEqual(ours.dtype, np.uint8)
        np.testing.assert_array_equal(ours, theirs)
        # The module's tone map of the array is the renderer's of its last image.
        np.testing.assert_array_equal(lobelight.tone_map(image), ours)
        # Saved, it reads back as it was.
        saved = Path(self.dir.name) / "saved.png"
        lobelight.save(saved, ours)
        np.testing.assert_array_equal(read_png(saved)[..., :3], ours)
        lobelight.save(Path(self.dir.name) / "saved.exr", image)
        with self.assertRaises(lobelight.LobelightError):
            lobelight.save(Path(self.dir.name) / "saved.png", image)

    def test_another_view_from_the_same_bake(self):
        side = self.renderer.render(eye=[1.5, 0.2, 3.5], width=24, height=16, spp=4)
        self.assertEqual(side.shape, (16, 24, 3))
        self.assertTrue(np.isfinite(side).all())
        self.assertGreater(float(side.mean()), 0.01)

    def test_object_ids_name_the_surfaces(self):
        ids = self.renderer.object_ids()
        self.assertEqual(ids.shape, (40, 40))
        self.assertEqual(ids.dtype, np.uint16)
        seen = {int(i) for i in np.unique(ids)} - {0, 65535}
        self.assertTrue(seen)
        self.assertLessEqual(max(seen), len(self.scene.surfaces))
        ball = 1 + next(k for k, s in enumerate(self.scene.surfaces) if "sphere" in s)
        self.assertIn(ball, seen)

    def test_the_path_tracer_agrees_on_the_mean(self):
        path = self.renderer.render(method="path", spp=64)
        ratio = float(path.mean()) / float(self.image.mean())
        self.assertAlmostEqual(ratio, 1.0, delta=0.1)

    def test_a_kept_bake_loads_and_draws_the_same_image(self):
        cache = Path(self.dir.name) / "box.bake"
        first = lobelight.Renderer(self.scene, engine="cpu")
        self.assertFalse(first.bake(cache=cache)["cache_hit"])
        again = lobelight.Renderer(self.scene, engine="cpu")
        report = again.bake(cache=cache)
        self.assertTrue(report["cache_hit"])
        np.testing.assert_array_equal(again.render(), first.render())

    def test_drawing_releases_the_gil(self):
        ticks = []
        stop = threading.Event()

        def tick():
            while not stop.is_set():
                ticks.append(1)
                stop.wait(0.001)

        thread = threading.Thread(target=tick)
        thread.start()
        try:
            self.renderer.render(spp=16)
        finally:
            stop.set()
            thread.join()
        # A thread that held the GIL through the draw would leave the ticker at one or two.
        self.assertGreater(len(ticks), 10)


class SceneFromArrays(unittest.TestCase):
    def test_points_as_arrays_draw_what_the_same_points_in_a_file_draw(self):
        pts, normals = ball_points()
        with tempfile.TemporaryDirectory() as d:
            ply = Path(d) / "ball.ply"
            write_ply(ply, pts, normals)
            # The box's file with its sphere swapped for the points, by file and by array.
            head = BOX.split("[[object]]\nshape = \"sphere\"")[0]
            by_file = head + '[[object]]\nshape = "model"\npath = "ball.ply"\nmaterial = "glossy"\n'
            scene_path = Path(d) / "ball.toml"
            scene_path.write_text(by_file)
            from_file = lobelight.load(scene_path)
            tables = {
                "camera": {"eye": [0.0, 0.0, 3.9], "target": [0.0, 0.0, 0.0], "fov": 39.3,
                           "resolution": [40, 40]},
                "bake": {"photons": 60000},
                "materials": {"white": {"diffuse": [0.8, 0.8, 0.8]},
                              "red": {"diffuse": [0.6, 0.05, 0.05]},
                              "glossy": {"diffuse": [0.2, 0.2, 0.3], "specular": 0.4,
                                         "roughness": 0.15}},
                "lights": [{"type": "area", "center": [0.0, 0.99, 0.0], "size": [0.5, 0.5],
                            "normal": [0.0, -1.0, 0.0], "u_axis": [1.0, 0.0, 0.0],
                            "radiance": [12.0, 12.0, 12.0]}],
            }
            box = {"shape": "cornell_box", "material": "white", "left_material": "red",
                   "right_material": "white", "spacing": 0.08}
            from_arrays = lobelight.build(
                [box, lobelight.points(pts, normals=normals, material="glossy")], **tables)
            self.assertEqual(from_arrays.splats, from_file.splats)
            a = lobelight.Renderer(from_file, engine="cpu").render(spp=4)
            b = lobelight.Renderer(from_arrays, engine="cpu").render(spp=4)
            np.testing.assert_array_equal(a, b)

    def test_a_mesh_as_arrays(self):
        vertices = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float64)
        faces = np.array([[0, 1, 2], [0, 2, 3]], np.int64)
        scene = lobelight.build(
            [lobelight.points(vertices, faces=faces, spacing=0.1)],
            lights=[{"type": "directional", "direction": [0, 0, -1], "irradiance": [1, 1, 1]}],
            camera={"eye": [0, 0, 3], "target": [0, 0, 0], "resolution": [16, 16]},
            bake={"photons": 10000})
        self.assertGreater(scene.splats, 100)
        image = lobelight.Renderer(scene, engine="cpu").render(spp=1)
        self.assertGreater(float(image[8, 8].mean()), 0.0)


class BadInput(unittest.TestCase):
    def test_a_scene_file_s_error_is_the_command_s_line(self):
        with tempfile.TemporaryDirectory() as d:
            path = Path(d) / "bad.toml"
            path.write_text(BOX.replace("fov = 39.3", "fov = \"wide\""))
            with self.assertRaises(lobelight.LobelightError) as raised:
                lobelight.load(path)
            done = command("info", path)
            self.assertNotEqual(done.returncode, 0)
            self.assertEqual(f"lobelight: {raised.exception}", done.stderr.strip().splitlines()[-1])
            self.assertIn("line", str(raised.exception))

    def test_bad_arrays_raise(self):
        pts, normals = ball_points(200)
        light = [{"type": "point", "position": [0, 2, 0], "power": [10, 10, 10]}]
        cases = {
            "not finite": pts.copy(),
            "n × 3": pts[:, :2],
            "normals for": None,
        }
        cases["not finite"][17, 1] = np.nan
        for why, value in cases.items():
            obj = (lobelight.points(pts, normals=normals[:10]) if value is None
                   else lobelight.points(value))
            with self.subTest(why), self.assertRaises(lobelight.LobelightError) as raised:
                lobelight.build([obj], lights=light)
            self.assertIn(why, str(raised.exception))
        with self.assertRaises(lobelight.LobelightError) as raised:
            lobelight.build([lobelight.points(pts, radii=-np.ones(len(pts)))], lights=light)
        self.assertIn("radius #0", str(raised.exception))

    def test_bad_parameters_raise(self):
        scene = lobelight.from_toml(BOX)
        with self.assertRaises(lobelight.LobelightError):
            lobelight.Renderer(scene, engine="quantum")
        renderer = lobelight.Renderer(scene, engine="cpu")
        for kwargs in ({"width": 0}, {"fov": 0.0}, {"eye": [0.0, 0.0, 0.0]}, {"method": "magic"},
                       {"eye": [float("nan"), 0.0, 1.0]}):
            with self.subTest(**{k: str(v) for k, v in kwargs.items()}):
                with self.assertRaises(lobelight.LobelightError):
                    renderer.render(**kwargs)
        with self.assertRaises(lobelight.LobelightError):
            renderer.tone_map()


class Examples(unittest.TestCase):
    def test_the_points_example_writes_its_images(self):
        with tempfile.TemporaryDirectory() as d:
            out = Path(d) / "points"
            done = subprocess.run([sys.executable, str(ROOT / "examples" / "points.py"),
                                   "--size", "48", "-o", str(out)],
                                  capture_output=True, text=True)
            self.assertEqual(done.returncode, 0, done.stderr)
            png = read_png(out.with_suffix(".png"))
            self.assertEqual(png.shape[:2], (48, 48))
            self.assertGreater(float(png.mean()), 10.0)
            self.assertGreater(out.with_suffix(".exr").stat().st_size, 48 * 48 * 4)


if __name__ == "__main__":
    unittest.main()
