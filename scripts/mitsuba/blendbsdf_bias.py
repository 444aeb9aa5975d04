#!/usr/bin/env python3
"""Mitsuba 3's `blendbsdf` of a diffuse and a smooth conductor under a uniform
sky, against the analytic value (docs/rendering.md, "Known differences").

A camera looks straight down at a large slab lit only by a constant
environment of radiance 1; with `max_depth` 2 (direct light only) a pixel's
value is the surface's albedo: `(1 - w) * diffuse + w * mirror` for a blend
of weight `w`. Mitsuba renders each single BSDF and a blend of two diffuse
BSDFs exactly; a blend of a diffuse and a mirror whose reflectances differ
comes out darker. This is why `to_mitsuba.py` refuses materials with both
`diffuse` and `reflect`.

Run with target/mitsuba-venv/bin/python (compare.py creates it).
"""
import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")


def albedo(bsdf, spp=512):
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 1, 0], target=[0, 0, 0], up=[0, 0, -1]),
                   "film": {"type": "hdrfilm", "width": 16, "height": 16, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent"}},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [1, 1, 1]}},
        "floor": {"type": "cube", "to_world": mi.ScalarTransform4f().translate([0, -1, 0]).scale([1000, 1, 1000]),
                  "bsdf": bsdf},
    }
    return np.array(mi.render(mi.load_dict(scene), spp=spp)).mean(axis=(0, 1))


def diffuse(c):
    return {"type": "diffuse", "reflectance": {"type": "rgb", "value": c}}


def mirror(c):
    return {"type": "conductor", "material": "none", "specular_reflectance": {"type": "rgb", "value": c}}


def blend(w, a, b):
    return {"type": "blendbsdf", "weight": w, "a": a, "b": b}


cases = [
    ("diffuse 0.63", diffuse([0.63] * 3), 0.63),
    ("mirror 0.7", mirror([0.7] * 3), 0.7),
    ("blend 0.5: diffuse 0.7, diffuse 0.63", blend(0.5, diffuse([0.7] * 3), diffuse([0.63] * 3)), 0.665),
    ("blend 0.5: diffuse 0.63, mirror 0.7", blend(0.5, diffuse([0.63] * 3), mirror([0.7] * 3)), 0.665),
    ("blend 0.1: diffuse 0.63, mirror 0.7", blend(0.1, diffuse([0.63] * 3), mirror([0.7] * 3)), 0.637),
    ("blend 0.5: diffuse 0.7, mirror 0.7", blend(0.5, diffuse([0.7] * 3), mirror([0.7] * 3)), 0.7),
]
print(f"Mitsuba {mi.__version__} scalar_rgb, 16x16 pixels x 512 samples")
print("| BSDF | Mitsuba | analytic |\n|---|---|---|")
for name, bsdf, want in cases:
    print(f"| {name} | {albedo(bsdf)[0]:.4f} | {want:.4f} |")
