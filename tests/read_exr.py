#!/usr/bin/env python3
"""Reads an OpenEXR file with the reference `OpenEXR` package and prints
everything the end-to-end tests check as JSON on stdout: the parts, the
header's compression and storage, the data and display windows (inclusive
corners [x0, y0, x1, y1]), the text attributes named `komplex.*`, each
channel's sample type and every sample (non-finite floats as the strings
"inf", "-inf", "nan"); for several files, a list of those objects.

Exit status 2 if the OpenEXR or numpy package is missing."""
import json
import math
import sys

try:
    import numpy as np
    import OpenEXR
except ImportError as e:  # pragma: no cover
    print(f"missing Python package: {e}", file=sys.stderr)
    sys.exit(2)


def sample(x):
    if isinstance(x, float) and not math.isfinite(x):
        return "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")
    return x


def read(path):
    with OpenEXR.File(path, separate_channels=True) as f:
        header = f.header()
        lo, hi = header["dataWindow"]
        dlo, dhi = header["displayWindow"]
        out = {
            "parts": len(f.parts),
            "compression": str(header["compression"]).split(".")[-1].split(":")[0],
            "storage": str(header["type"]).split(".")[-1].split(":")[0],
            "width": int(hi[0] - lo[0] + 1),
            "height": int(hi[1] - lo[1] + 1),
            "data_window": [int(v) for v in (*lo, *hi)],
            "display_window": [int(v) for v in (*dlo, *dhi)],
            "attributes": {k: v for k, v in header.items() if k.startswith("komplex.") and isinstance(v, str)},
            "channels": {},
        }
        for name, ch in f.channels().items():
            px = ch.pixels
            kind = {np.dtype("float32"): "f32", np.dtype("float16"): "f16", np.dtype("uint32"): "u32"}[px.dtype]
            values = px.astype(np.float64).ravel().tolist() if kind != "u32" else px.ravel().tolist()
            out["channels"][name] = {"type": kind, "samples": [sample(v) for v in values]}
    return out


if __name__ == "__main__":
    # One file: its object; several: a list of them, in order.
    files = [read(path) for path in sys.argv[1:]]
    json.dump(files[0] if len(files) == 1 else files, sys.stdout)
