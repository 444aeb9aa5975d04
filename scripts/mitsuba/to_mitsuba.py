#!/usr/bin/env python3
"""Converts a Komplex scene (JSON, docs/scene-format.md) to a Mitsuba 3 scene
dictionary for `mitsuba.load_dict`, for the subset the cross-check scenes use.

Geometry: a block that is
  - one sphere (any translate, uniform scale and rotation) -> `sphere`;
  - six half-spaces forming a box (three pairs of opposite, mutually
    orthogonal faces, after all transforms) -> `cube` with `to_world`;
  - one circular cylinder and two half-spaces perpendicular to its axis
    (a capped right cylinder) -> an open `cylinder` and two `disk`s.
Anything else (other quadrics, complements, more or fewer objects) is a
`ConversionError` naming the block.

Materials (path-integrator units, docs/scene-format.md):
  - `diffuse` only -> `diffuse` (Lambertian albedo);
  - `reflect` only -> `conductor` with `material: "none"` (a perfect mirror:
    Fresnel reflectance 1) scaled by `specular_reflectance`;
  - both: an error (Mitsuba's `blendbsdf` of a diffuse and a smooth
    conductor renders too dark where the two reflectances differ);
  - a transparent block with `transmit` and `ior` -> `dielectric` (exact
    Fresnel) with `int_ior` = `ior`, `ext_ior` = 1, reflection and
    transmission scaled by `transmit`;
  - `emission` -> an `area` emitter of that radiance on every shape of the
    block (one-sided along the outward normals, as ours);
  - `ambient` is ignored (the path integrator ignores it); a non-zero
    `specular` (Mitsuba 3 has no Phong lobe), textures, bump maps and
    per-object materials are errors.
Lights and settings: point lights -> `point` (intensity = `color`, W/sr);
`settings.background` -> `constant` emitter; `settings.max_depth` (bounces
after the primary hit, default 5) -> `path` integrator with `max_depth` =
ours + 2; camera -> `perspective` (`thinlens` when `lens_radius` > 0) with
`fov_axis: "diagonal"`; film `hdrfilm` with a box filter.

Usage as a script: `to_mitsuba.py SCENE.json` prints the dictionary (the
transforms as 4x4 matrices); `compare.py` imports `convert` and loads its
result with `mitsuba.load_dict(to_mitsuba_types(d))`.
"""
import json
import math
import sys

import numpy as np


class ConversionError(Exception):
    """A scene outside the converter's subset; the message names the block."""


TOL = 1e-9


# ---------------------------------------------------------------- transforms

def step_matrix(step, where):
    if not isinstance(step, dict) or len(step) != 1:
        raise ConversionError(f"{where}: a transform step must have exactly one key")
    (key, v), = step.items()
    m = np.eye(4)
    if key == "translate":
        m[:3, 3] = v
    elif key == "scale":
        s = [v, v, v] if isinstance(v, (int, float)) else v
        m[0, 0], m[1, 1], m[2, 2] = s
    elif key in ("rotate_x", "rotate_y", "rotate_z"):
        a = math.radians(v)
        # Multiples of 90 degrees exactly, as the renderer does.
        c, s = (round(math.cos(a)), round(math.sin(a))) if v % 90 == 0 else (math.cos(a), math.sin(a))
        i, j = {"rotate_x": (1, 2), "rotate_y": (2, 0), "rotate_z": (0, 1)}[key]
        m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    elif key == "matrix":
        m = np.array(v, dtype=float)
    else:
        raise ConversionError(f"{where}: unknown transform step `{key}`")
    return m


def chain(steps, where):
    """The matrix of a list of steps, the first step acting first."""
    m = np.eye(4)
    for k, step in enumerate(steps or []):
        m = step_matrix(step, f"{where}.transform[{k}]") @ m
    return m


def flatten(entries, outer, path, out):
    """Blocks in priority order, each with its block-to-world matrix."""
    for k, e in enumerate(entries):
        where = f"{path}[{k}]"
        if "group" in e:
            flatten(e["blocks"], outer @ chain(e.get("transform"), where), where + ".blocks", out)
        else:
            out.append((e, outer @ chain(e.get("transform"), where), where))
    return out


# ------------------------------------------------------------------ geometry

def plane_to_world(h, m):
    """The half-space a.x + d <= 0 carried by the affine map m: p' = p m^-1."""
    p = np.array(h, dtype=float) @ np.linalg.inv(m)
    n = np.linalg.norm(p[:3])
    return p[:3] / n, p[3] / n


def ortho_frame(n):
    """Two unit vectors completing n to a right-handed orthonormal frame."""
    a = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    e1 = np.cross(a, n)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(n, e1)


def affine(cols, origin):
    m = np.eye(4)
    m[:3, :3] = np.column_stack(cols)
    m[:3, 3] = origin
    return m


def sphere_shape(obj, m, name):
    s = obj["sphere"] or {}
    r = float(s.get("radius", 1.0))
    c = np.array(s.get("center", [0, 0, 0]), dtype=float)
    a = m[:3, :3] * r
    g = a.T @ a
    k = math.sqrt(g[0, 0])
    if not np.allclose(g, k * k * np.eye(3), rtol=1e-9, atol=0):
        raise ConversionError(f'block "{name}": a sphere scaled unevenly (an ellipsoid) is not supported')
    centre = m[:3, :3] @ c + m[:3, 3]
    return [{"type": "sphere", "center": centre.tolist(), "radius": k}]


def box_shape(objs, m, name):
    planes = [plane_to_world(o["halfspace"], m @ chain(o.get("transform"), name)) for o in objs]
    pairs, used = [], set()
    for i, (n, d) in enumerate(planes):
        if i in used:
            continue
        j = next((j for j in range(i + 1, 6) if j not in used and np.dot(n, planes[j][0]) < -1 + TOL), None)
        if j is None:
            raise ConversionError(f'block "{name}": six half-spaces that are not three pairs of opposite faces')
        used |= {i, j}
        # n.x <= -d and -n.x <= dj, i.e. -dj <= n.x <= -d.
        lo, hi = planes[j][1], -d
        if not lo < hi:
            raise ConversionError(f'block "{name}": an empty box')
        pairs.append((n, lo, hi))
    ns = [p[0] for p in pairs]
    for a in range(3):
        for b in range(a + 1, 3):
            if abs(np.dot(ns[a], ns[b])) > TOL:
                raise ConversionError(f'block "{name}": six half-spaces that are not a rectangular box')
    if np.dot(np.cross(ns[0], ns[1]), ns[2]) < 0:
        pairs[2] = (-ns[2], -pairs[2][2], -pairs[2][1])  # keep to_world orientation-preserving
    centre = sum(n * (lo + hi) / 2 for n, lo, hi in pairs)
    cols = [n * (hi - lo) / 2 for n, lo, hi in pairs]
    return [{"type": "cube", "to_world": affine(cols, centre)}]


def cylinder_shape(cyl, caps, m, name):
    c = cyl["cylinder"] or {}
    r = float(c.get("radius", 1.0))
    axis = c.get("axis", "y")
    # Unit tube along y, scaled by r, turned to `axis`, then the object's and block's maps.
    turn = {"y": np.eye(3), "x": np.array([[0, 1.0, 0], [1, 0, 0], [0, 0, 1]]),
            "z": np.array([[1.0, 0, 0], [0, 0, 1], [0, 1, 0]])}[axis]
    mo = m @ chain(cyl.get("transform"), name)
    a = mo[:3, :3] @ turn
    u, ex, ez = a[:, 1], a[:, 0] * r, a[:, 2] * r
    rad = np.linalg.norm(ex)
    if not (abs(np.linalg.norm(ez) - rad) <= TOL * rad and abs(np.dot(ex, ez)) <= TOL * rad * rad
            and abs(np.dot(ex, u)) <= TOL * rad * np.linalg.norm(u) and abs(np.dot(ez, u)) <= TOL * rad * np.linalg.norm(u)):
        raise ConversionError(f'block "{name}": a cylinder that is not circular and right after its transforms')
    u = u / np.linalg.norm(u)
    o = mo[:3, 3]
    ts = []
    for h in caps:
        n, d = plane_to_world(h["halfspace"], m @ chain(h.get("transform"), name))
        cos = np.dot(n, u)
        if abs(abs(cos) - 1) > TOL:
            raise ConversionError(f'block "{name}": a cylinder cap that is not perpendicular to its axis')
        ts.append((-(np.dot(n, o) + d) / cos, cos > 0))
    ts.sort()
    (t0, up0), (t1, up1) = ts
    if up0 or not up1 or not t0 < t1:
        raise ConversionError(f'block "{name}": cylinder caps that do not bound a finite piece')
    p0, p1 = o + t0 * u, o + t1 * u
    shapes = [{"type": "cylinder", "p0": p0.tolist(), "p1": p1.tolist(), "radius": rad}]
    for p, n in ((p0, -u), (p1, u)):
        e1, e2 = ortho_frame(n)
        shapes.append({"type": "disk", "to_world": affine([e1 * rad, e2 * rad, n], p)})
    return shapes


def block_shapes(block, m, name):
    objs = block["objects"]
    for o in objs:
        if o.get("complement"):
            raise ConversionError(f'block "{name}": complements are not supported')
        if "material" in o and o["material"] != block.get("material"):
            raise ConversionError(f'block "{name}": per-object materials are not supported')
    kinds = sorted(next(k for k in o if k in ("sphere", "cylinder", "halfspace", "cone", "paraboloid",
                                              "hyperboloid", "quadric")) for o in objs)
    if kinds == ["sphere"]:
        o = objs[0]
        return sphere_shape(o, m @ chain(o.get("transform"), name), name)
    if kinds == ["halfspace"] * 6:
        return box_shape(objs, m, name)
    if kinds == ["cylinder", "halfspace", "halfspace"]:
        cyl = next(o for o in objs if "cylinder" in o)
        return cylinder_shape(cyl, [o for o in objs if "halfspace" in o], m, name)
    raise ConversionError(f'block "{name}": only a sphere, a box of six half-spaces or a capped cylinder '
                          f'converts to Mitsuba (this block is {", ".join(kinds)})')


# ----------------------------------------------------------------- materials

def rgb(v):
    return {"type": "rgb", "value": [float(x) for x in v]}


def colour(mat, key, name):
    v = mat.get(key, [0, 0, 0])
    if not isinstance(v, list):
        raise ConversionError(f'block "{name}": a textured `{key}` is not supported')
    return [float(x) for x in v]


def bsdf_and_emitter(block, materials, name):
    mname = block.get("material")
    if mname is None:
        mat = {"diffuse": [0.8, 0.8, 0.8]}
    elif mname not in materials:
        raise ConversionError(f'block "{name}": unknown material "{mname}"')
    else:
        mat = materials[mname]
    if "bump" in mat:
        raise ConversionError(f'block "{name}": bump maps are not supported')
    if max(colour(mat, "specular", name)) > 0:
        raise ConversionError(f'block "{name}": a Phong `specular` lobe has no Mitsuba 3 counterpart')
    d, r, t = colour(mat, "diffuse", name), colour(mat, "reflect", name), colour(mat, "transmit", name)
    if block.get("transparent") and max(t) > 0:
        if max(d) > 0 or max(r) > 0:
            raise ConversionError(f'block "{name}": a glass with `diffuse` or `reflect` is not supported')
        bsdf = {"type": "dielectric", "int_ior": float(mat.get("ior", 1.0)), "ext_ior": 1.0,
                "specular_reflectance": rgb(t), "specular_transmittance": rgb(t)}
    elif block.get("transparent"):
        raise ConversionError(f'block "{name}": a transparent block without `transmit` is not supported')
    elif max(r) == 0:
        bsdf = {"type": "diffuse", "reflectance": rgb(d)}
    elif max(d) == 0:
        bsdf = {"type": "conductor", "material": "none", "specular_reflectance": rgb(r)}
    else:
        # komplex sums the lobes; Mitsuba's `blendbsdf` of a diffuse and a smooth conductor
        # would express it, but under Mitsuba 3.9.1 it renders too dark wherever the two
        # reflectances differ (docs/rendering.md), so the cross-check does not use it.
        raise ConversionError(f'block "{name}": `diffuse` and `reflect` together are not supported '
                              "(Mitsuba's blendbsdf of a diffuse and a mirror is biased)")
    e = mat.get("emission")
    emitter = {"type": "area", "radiance": rgb(e)} if e is not None and max(e) > 0 else None
    return bsdf, emitter


# -------------------------------------------------------------------- camera

def look_at(eye, direction, up):
    """Mitsuba's `look_at` (camera space: x left, y up, z forward) as a matrix."""
    d = np.array(direction, dtype=float)
    d /= np.linalg.norm(d)
    left = np.cross(np.array(up, dtype=float), d)
    left /= np.linalg.norm(left)
    return affine([left, np.cross(d, left), d], np.array(eye, dtype=float))


def sensor(cam, spp, width, height):
    if cam.get("projection", "perspective") != "perspective":
        raise ConversionError("camera: only the perspective projection is supported")
    eye, direction = cam["eye"], cam["direction"]
    w, h = width or cam.get("width", 640), height or cam.get("height", 480)
    # Mitsuba starts its rays on the near clipping plane (default 0.01 away): ours start at the eye.
    s = {"type": "perspective", "fov": float(cam.get("aperture", 50)), "fov_axis": "diagonal", "near_clip": 1e-6,
         "to_world": look_at(eye, direction, cam.get("up", [0, 1, 0])),
         "film": {"type": "hdrfilm", "width": int(w), "height": int(h), "rfilter": {"type": "box"},
                  "pixel_format": "rgb", "component_format": "float32"},
         "sampler": {"type": "independent", "sample_count": int(spp)}}
    lens = float(cam.get("lens_radius", 0))
    if lens > 0:
        s["type"] = "thinlens"
        s["aperture_radius"] = lens
        s["focus_distance"] = float(cam.get("focus_distance", np.linalg.norm(direction)))
    return s


# --------------------------------------------------------------------- scene

def scene_size(scene, width=None, height=None):
    """The image size after --width/--height, as `komplex render` computes it."""
    cam = scene["camera"]
    w0, h0 = cam.get("width", 640), cam.get("height", 480)
    if width and height:
        return width, height
    if width:
        return width, max(1, round(width * h0 / w0))
    if height:
        return max(1, round(height * w0 / h0)), height
    return w0, h0


def convert(scene, spp=16, width=None, height=None):
    """The Mitsuba scene dictionary of a Komplex scene (a parsed JSON object)."""
    settings = scene.get("settings", {})
    if settings.get("integrator", "whitted") != "path":
        raise ConversionError('settings.integrator: the cross-check compares the "path" integrator')
    w, h = scene_size(scene, width, height)
    out = {"type": "scene",
           "integrator": {"type": "path", "max_depth": int(settings.get("max_depth", 5)) + 2},
           "sensor": sensor(scene["camera"], spp, w, h)}
    bg = settings.get("background", [0, 0, 0])
    if max(bg) > 0:
        out["background"] = {"type": "constant", "radiance": rgb(bg)}
    for k, light in enumerate(scene.get("lights", [])):
        c = light.get("color", [1, 1, 1])
        if light.get("diffuse", c) != c or light.get("specular", c) != c:
            raise ConversionError(f"lights[{k}]: separate diffuse and specular colours are not supported")
        out[f"light {k}"] = {"type": "point", "position": light["position"], "intensity": rgb(c)}
    materials = scene.get("materials", {})
    blocks = flatten(scene["blocks"], np.eye(4), "blocks", [])
    for k, (block, m, where) in enumerate(blocks):
        name = block.get("name", f"block {k + 1}")
        if block.get("transparent") and any(b.get("transparent") for b, _, _ in blocks if b is not block):
            # int_ior/ext_ior assume glass in air: nested or touching media would need the partition.
            raise ConversionError(f'block "{name}": only one transparent block is supported')
        bsdf, emitter = bsdf_and_emitter(block, materials, name)
        for j, shape in enumerate(block_shapes(block, m, name)):
            shape["bsdf"] = bsdf
            if emitter:
                shape["emitter"] = emitter
            out[f"{k + 1:04d} {name} {j}"] = shape
    return out


def to_mitsuba_types(d):
    """The dictionary with its 4x4 matrices as Mitsuba transforms, for `load_dict`."""
    import mitsuba as mi
    if isinstance(d, dict):
        return {k: to_mitsuba_types(v) for k, v in d.items()}
    if isinstance(d, np.ndarray):
        return mi.ScalarTransform4f(d.tolist())
    return d


def main(argv):
    if len(argv) != 2:
        sys.exit("usage: to_mitsuba.py SCENE.json")
    with open(argv[1]) as f:
        scene = json.load(f)
    try:
        d = convert(scene)
    except ConversionError as e:
        sys.exit(f"error: {argv[1]}: {e}")
    json.dump(d, sys.stdout, indent=1, default=lambda a: a.tolist())
    print()


if __name__ == "__main__":
    main(sys.argv)
