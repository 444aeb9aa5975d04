#!/usr/bin/env python3
"""compare_exr.py A.exr B.exr: exit 0 if the two OpenEXR files hold the
same image: equal data and display windows, the same channel names, sample
types and subsampling, and every sample bit for bit equal (so NaN equals a
NaN of the same bits, and 0.0 differs from -0.0). Otherwise prints the
first difference and exits 1; 2 if the OpenEXR or numpy package is missing.
Reads the files with the reference OpenEXR package, not with komplex."""
import sys

try:
    import numpy as np
    import OpenEXR
except ImportError as e:  # pragma: no cover
    print(f"compare_exr.py: missing Python package: {e}", file=sys.stderr)
    sys.exit(2)


def window(header, key):
    lo, hi = header[key]
    return (tuple(int(v) for v in lo), tuple(int(v) for v in hi))


def read(path):
    try:
        f = OpenEXR.File(path, separate_channels=True)
    except Exception as e:
        raise SystemExit(f"compare_exr.py: cannot read {path}: {e}")
    with f:
        if len(f.parts) != 1:
            raise SystemExit(f"compare_exr.py: {path}: {len(f.parts)} parts, expected 1")
        h = f.header()
        channels = {
            name: (ch.pixels.dtype, ch.xSampling, ch.ySampling, ch.pixels.copy())
            for name, ch in f.channels().items()
        }
        return window(h, "dataWindow"), window(h, "displayWindow"), channels


def main(a_path, b_path):
    a, b = read(a_path), read(b_path)
    for i, what in enumerate(["data window", "display window"]):
        if a[i] != b[i]:
            return f"{what}: {a[i]} in {a_path}, {b[i]} in {b_path}"
    if sorted(a[2]) != sorted(b[2]):
        return f"channels: {sorted(a[2])} in {a_path}, {sorted(b[2])} in {b_path}"
    for name in sorted(a[2]):
        (ta, xa, ya, pa), (tb, xb, yb, pb) = a[2][name], b[2][name]
        if (ta, xa, ya) != (tb, xb, yb):
            return f"channel {name}: type {ta} sampling {xa}x{ya} in {a_path}, {tb} {xb}x{yb} in {b_path}"
        if pa.shape != pb.shape:
            return f"channel {name}: shape {pa.shape} in {a_path}, {pb.shape} in {b_path}"
        bits = np.dtype(f"u{pa.dtype.itemsize}")
        diff = np.argwhere(pa.view(bits) != pb.view(bits))
        if len(diff):
            y, x = (int(v) for v in diff[0])
            return (f"channel {name}: {len(diff)} samples differ, the first at row {y} column {x} "
                    f"(of the data window): {pa[y, x]!r} in {a_path}, {pb[y, x]!r} in {b_path}")
    return None


if __name__ == "__main__":
    if len(sys.argv) != 3:
        print("usage: compare_exr.py A.exr B.exr", file=sys.stderr)
        sys.exit(2)
    difference = main(sys.argv[1], sys.argv[2])
    if difference:
        print(f"compare_exr.py: the images differ: {difference}", file=sys.stderr)
        sys.exit(1)
    print(f"{sys.argv[1]} and {sys.argv[2]}: the same image")
