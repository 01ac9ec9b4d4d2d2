"""lobelight from Python: splat scenes with global illumination, images as numpy arrays.

    import lobelight
    scene = lobelight.load("scenes/cornell.toml")     # or lobelight.build(...) from arrays
    renderer = lobelight.Renderer(scene)              # the engine, chosen once
    image = renderer.render()                         # linear HDR, height × width × 3, float32
    png = lobelight.tone_map(image)                   # uint8, as the command's PNG
    lobelight.save("out.png", png)                    # or the float32 image as .exr

A scene built here is the scene file's tables as dicts (docs/scenes.md): `camera`, `lights`
(the file's `[[light]]`), `materials`, `objects` (its `[[object]]`) and `bake`. An object that
holds arrays (`points`, and optionally `normals`, `colors`, `radii`, `faces`) is a model made
of them, handed to the library with one copy. The heavy work (loading, baking, drawing)
releases the GIL. Errors raise `LobelightError` with the command's one-line message.
"""

import math
from pathlib import Path

import numpy as np

from ._lobelight import LobelightError, Renderer, Scene, __version__, save, tone_map

__all__ = ["LobelightError", "Renderer", "Scene", "build", "from_toml", "load", "points", "save",
           "tone_map", "__version__"]

# The keys of an object that hold arrays, and the dtype and columns each is handed over in.
_ARRAYS = {"points": (np.float32, 3), "normals": (np.float32, 3), "colors": (np.float32, 3),
           "radii": (np.float32, None), "faces": (np.uint32, 3)}


def load(path):
    """Reads and builds a scene file (TOML)."""
    return Scene.load(str(path))


def from_toml(text, path="scene.toml"):
    """Builds a scene from TOML text; `path` names it in errors and anchors model paths."""
    return Scene.parse(text, str(path), [])


def points(points, normals=None, colors=None, radii=None, faces=None, **keys):
    """An object made of arrays: `points` (n × 3), and optionally `normals` (n × 3; else
    estimated from neighbours), `colors` (n × 3, sRGB in [0, 1], or uint8), `radii` (n; else
    from the neighbour spacing) or `faces` (m × 3 vertex indices: a mesh, sampled at
    `spacing`). Other keys are the scene file's for a model: `material`, `fit`, `anchor`,
    `translate`, `rotate`, `scale`, `sides`, `vertex_colors`, `spacing`."""
    obj = {"shape": "model", "points": points}
    for name, value in (("normals", normals), ("colors", colors), ("radii", radii),
                        ("faces", faces)):
        if value is not None:
            obj[name] = value
    obj.update(keys)
    return obj


def build(objects, lights=(), camera=None, materials=None, bake=None, base_dir=".", **top):
    """A scene from the scene file's tables as Python values: `objects` (a list of dicts, the
    file's `[[object]]`, or `points(...)`), `lights` (its `[[light]]`), `camera`, `materials`
    ({name: dict}), `bake`, and any other top-level key (`max_memory`). `base_dir` anchors
    model paths. Arrays are handed over without being written anywhere."""
    arrays = []
    tables = []
    for k, obj in enumerate(objects):
        obj = dict(obj)
        parts = {key: obj.pop(key) for key in list(obj) if key in _ARRAYS}
        if parts:
            if "points" not in parts:
                raise LobelightError(f"object #{k + 1}: arrays need `points`")
            name = f"object {k + 1}"
            obj.setdefault("shape", "model")
            obj["array"] = name
            arrays.append((name, *(_array(name, key, parts.get(key)) for key in _ARRAYS)))
        tables.append(obj)
    doc = dict(top)
    if camera is not None:
        doc["camera"] = camera
    if materials:
        doc["materials"] = materials
    if bake:
        doc["bake"] = bake
    doc["light"] = list(lights)
    doc["object"] = tables
    path = Path(base_dir) / "<built in Python>"
    return Scene.parse(_toml(doc), str(path), arrays)


def _array(name, key, value):
    """`value` as the contiguous array the native side takes, or None."""
    if value is None:
        return None
    dtype, columns = _ARRAYS[key]
    a = np.asarray(value)
    if key == "colors" and a.dtype == np.uint8:
        a = a / 255.0
    if key == "faces":
        if not np.issubdtype(a.dtype, np.integer):
            raise LobelightError(f"array '{name}': faces must be integers, got {a.dtype}")
        if a.size and (a.min() < 0 or a.max() > np.iinfo(np.uint32).max):
            raise LobelightError(f"array '{name}': a face's vertex index is out of range")
    a = np.ascontiguousarray(a, dtype=dtype)
    want = (columns,) if columns else ()
    if a.ndim != 1 + len(want) or a.shape[1:] != want:
        shape = f"n × {columns}" if columns else "n"
        raise LobelightError(f"array '{name}': {key} must be {shape}, got {a.shape}")
    return a


def _toml(doc):
    """TOML text of a dict of tables, values and arrays of tables (what scene files hold)."""
    lines = []
    for key, value in doc.items():
        if not isinstance(value, (dict, list)) or (isinstance(value, list)
                                                   and not all(isinstance(v, dict) for v in value)):
            lines.append(f"{_key(key)} = {_value(value)}")
    for key, value in doc.items():
        if isinstance(value, dict):
            _table(lines, [key], value)
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for item in value:
                lines.append(f"\n[[{_key(key)}]]")
                lines.extend(f"{_key(k)} = {_value(v)}" for k, v in item.items())
    return "\n".join(lines) + "\n"


def _table(lines, path, table):
    lines.append(f"\n[{'.'.join(_key(p) for p in path)}]")
    nested = []
    for key, value in table.items():
        if isinstance(value, dict):
            nested.append((key, value))
        else:
            lines.append(f"{_key(key)} = {_value(value)}")
    for key, value in nested:
        _table(lines, path + [key], value)


def _key(key):
    key = str(key)
    if key and all(c.isalnum() or c in "_-" for c in key):
        return key
    return _string(key)


def _string(s):
    escaped = s.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
    return f'"{escaped}"'


def _value(v):
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        v = float(v)
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, (str, Path)):
        return _string(str(v))
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }"
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_value(x) for x in (v.tolist() if isinstance(v, np.ndarray) else v)) + "]"
    raise LobelightError(f"a scene value must be a number, string, list or table, got {type(v).__name__}")
