#!/usr/bin/env python3
"""Cross-check of komplex's path integrator against Mitsuba 3 (issue 36).

For each scene, at the same image size, samples per pixel and threads:

0. Geometry. Mitsuba's mean hit distance over each pixel (its `depth` AOV)
   against komplex's `Z` at the pixel centre: the camera, the pixel
   orientation and the converted shapes line up before colours are compared.
1. Agreement. Each renderer renders `--batches` images with independent seeds
   at `--check-spp` samples per pixel. For every region (a 4x4 grid, the
   pixels of each block as komplex's `id.block` channel sees them, and the
   scene's named regions) the mean of each colour channel is taken per image;
   the regions' means and standard errors (spread over the independent images,
   std / sqrt(batches)) are compared channel by channel: they agree when the
   difference is within 3 standard errors of the difference.
2. Time against error. A reference is the mean of both renderers at
   `--ref-spp`; each renderer then renders at each of `--spp` (e.g. 4 16 64
   256) `--repeats` times with independent seeds, timed by the wall clock;
   the RMSE against the reference (all pixels, R G B; the reference's own
   noise subtracted) and the median time are reported, with the ratio of
   the times the two need to reach the same error.
   komplex's time is the whole `komplex render` process (parse, load, render,
   EXR written); Mitsuba's is `mitsuba.render` alone (its scene loaded before).

Mitsuba runs its `scalar_rgb` variant (its LLVM variants fail to compile on
these machines) with `drjit.set_thread_count(threads)`; the `path` integrator
with `max_depth` = ours + 2, the `independent` sampler, a box pixel filter.

The default scenes: scenes/cornell.json, scenes/caustics.json and
scripts/mitsuba/scenes/lights-and-lens.json (a point light, a spherical lamp,
a constant sky and a thin lens).

Usage (after `cargo build --release`):

    python3 scripts/mitsuba/compare.py [--width 128] [--threads 2] [SCENE.json ...]

The first run creates target/mitsuba-venv and installs requirements.txt into
it; the script then re-runs itself there. It prints a Markdown report (also
written to `--out`, default target/mitsuba/report.md) and, with `--plot
FILE.png`, plots RMSE against time.
"""
import argparse
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
VENV = ROOT / "target" / "mitsuba-venv"
REQUIREMENTS = HERE / "requirements.txt"

# Named regions (fractions of the image: x0, y0, x1, y1 with y from the top),
# beside the 4x4 grid and the per-block regions.
NAMED = {
    "cornell": {"ceiling beside the lamp": (0.3, 0.02, 0.7, 0.08), "floor under the ball": (0.15, 0.9, 0.45, 0.98)},
    "caustics": {"caustic": (0.58, 0.53, 0.67, 0.6), "shadow beyond the caustic": (0.73, 0.5, 0.88, 0.58)},
}


def ensure_venv():
    """Re-runs this script in target/mitsuba-venv, creating it if needed."""
    py = VENV / "bin" / "python"
    if Path(sys.prefix).resolve() == VENV.resolve():
        return
    stamp = VENV / "requirements.txt"
    if not py.exists() or not stamp.exists() or stamp.read_text() != REQUIREMENTS.read_text():
        print(f"creating {VENV.relative_to(ROOT)} from {REQUIREMENTS.relative_to(ROOT)}", file=sys.stderr)
        subprocess.run([sys.executable, "-m", "venv", str(VENV)], check=True)
        subprocess.run([str(py), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
                        "-r", str(REQUIREMENTS)], check=True)
        stamp.write_text(REQUIREMENTS.read_text())
    os.execv(str(py), [str(py), __file__, *sys.argv[1:]])


def run(cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout.strip()


class Komplex:
    """komplex render, one process per image."""

    def __init__(self, binary, threads, width, height, tmp):
        self.binary, self.threads, self.width, self.height, self.tmp = binary, threads, width, height, tmp

    def render(self, scene_path, spp, seed, aovs=False):
        import numpy as np
        import OpenEXR
        out = Path(self.tmp) / "komplex.exr"
        cmd = [self.binary, "render", str(scene_path), "-o", str(out), "--spp", str(spp), "--seed", str(seed),
               "--threads", str(self.threads), "--width", str(self.width), "--height", str(self.height)]
        t = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True)
        seconds = time.perf_counter() - t
        if p.returncode != 0:
            sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr}")
        with OpenEXR.File(str(out), separate_channels=True) as f:
            ch = f.channels()
            img = np.stack([ch[c].pixels.astype(np.float64) for c in "RGB"], axis=-1)
            aov = {"id": ch["id.block"].pixels.astype(np.int64), "Z": ch["Z"].pixels.astype(np.float64)} if aovs else None
        return img, seconds, aov


class Mitsuba:
    """Mitsuba 3 scalar_rgb, the scene loaded once per size."""

    def __init__(self, threads, width, height):
        import drjit as dr
        import mitsuba as mi
        mi.set_variant("scalar_rgb")
        dr.set_thread_count(threads)
        self.mi, self.dr, self.width, self.height, self.loaded = mi, dr, width, height, {}
        self.threads = dr.thread_count()

    def load(self, scene_path, integrator=None):
        sys.path.insert(0, str(HERE))
        from to_mitsuba import convert, to_mitsuba_types
        key = (scene_path, json.dumps(integrator))
        if key not in self.loaded:
            with open(scene_path) as f:
                d = convert(json.load(f), width=self.width, height=self.height)
            if integrator:
                # The AOVs of the pinhole camera, as komplex's (which come from the pinhole ray).
                d["integrator"] = integrator
                d["sensor"]["type"] = "perspective"
                d["sensor"].pop("aperture_radius", None)
                d["sensor"].pop("focus_distance", None)
            self.loaded[key] = self.mi.load_dict(to_mitsuba_types(d))
        return self.loaded[key]

    def render(self, scene_path, spp, seed, integrator=None):
        import numpy as np
        scene = self.load(scene_path, integrator)
        t = time.perf_counter()
        img = np.array(self.mi.render(scene, spp=spp, seed=seed), dtype=np.float64)
        return img, time.perf_counter() - t


def regions(scene, name, ids, h, w):
    """(name, boolean mask) of the 4x4 grid, each block's pixels and the named regions."""
    import numpy as np
    sys.path.insert(0, str(HERE))
    from to_mitsuba import flatten
    out = []
    for r in range(4):
        for c in range(4):
            m = np.zeros((h, w), bool)
            m[r * h // 4:(r + 1) * h // 4, c * w // 4:(c + 1) * w // 4] = True
            out.append((f"grid row {r} col {c}", m))
    blocks = flatten(scene["blocks"], np.eye(4), "blocks", [])
    for k, (b, _, _) in enumerate(blocks):
        m = ids == k + 1
        if m.sum() >= 16:
            out.append((f'block "{b.get("name", f"block {k + 1}")}"', m))
    for rname, (x0, y0, x1, y1) in NAMED.get(name, {}).items():
        m = np.zeros((h, w), bool)
        m[round(y0 * h):round(y1 * h), round(x0 * w):round(x1 * w)] = True
        if m.any():
            out.append((rname, m))
    return out


def geometry(scene_path, aov, theirs, lines):
    """Camera and shapes line up: Mitsuba's mean distance to the first hit (its `depth` AOV,
    256 samples spread over each pixel) against komplex's `Z` at the pixel centre, on the pixels
    whose 3x3 neighbourhood komplex sees on one block. They line up when the median relative
    difference is below 0.1 %, 95 % of the pixels agree within 1 % (a mean over a pixel of a grazing
    floor or a silhouette differs from its centre value by more; half a pixel's shift by far more)
    and Mitsuba hits nothing where komplex sees nothing."""
    import numpy as np
    depth = theirs.render(scene_path, 256, seed=1, integrator={"type": "aov", "aovs": "dd:depth"})[0][..., 0]
    ids, z = aov["id"], aov["Z"]
    h, w = ids.shape
    inner = np.zeros_like(ids, bool)
    inner[1:-1, 1:-1] = True
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            inner[1:-1, 1:-1] &= ids[1 + dy:h - 1 + dy, 1 + dx:w - 1 + dx] == ids[1:-1, 1:-1]
    hit = inner & (ids > 0)
    miss = inner & (ids == 0)
    rel = np.abs(depth[hit] - z[hit]) / z[hit]
    close = int((rel < 1e-2).sum())
    ok = np.median(rel) < 1e-3 and close >= 0.95 * hit.sum() and not (depth[miss] > 0).any()
    lines += [f"Geometry: on {int(hit.sum())} pixels inside one block, the median relative difference of the "
              f"distances is {np.median(rel):.1e}, {close} are within 1 %; on {int(miss.sum())} pixels komplex sees "
              f"nothing, Mitsuba hits something on {int((depth[miss] > 0).sum())}: "
              f"{'they line up' if ok else '**they do not line up**'}.", ""]
    return ok


def fmt(x, e):
    return f"{x:.4f} ± {e:.4f}"


def t_two_sided(t, dof):
    """P(|T| >= t) for Student's t with `dof` degrees of freedom (Simpson's
    rule on the density from 0 to t; exact to about 1e-12, enough for the
    tail probabilities of a family-wise test)."""
    if not math.isfinite(t):
        return 0.0
    if dof > 1e6:
        return math.erfc(t / math.sqrt(2.0))
    c = math.exp(math.lgamma((dof + 1) / 2) - math.lgamma(dof / 2)) / math.sqrt(dof * math.pi)
    pdf = lambda x: c * (1 + x * x / dof) ** (-(dof + 1) / 2)
    n = 4000
    h = t / n
    inner = sum((4 if k % 2 else 2) * pdf(k * h) for k in range(1, n))
    return max(0.0, 1.0 - 2.0 * h / 3.0 * (pdf(0.0) + inner + pdf(t)))


def welch_p(diff, so, sm, se, batches):
    """The two-sided p-value of each channel's difference: Welch's t with
    the Welch–Satterthwaite degrees of freedom of the two batch means."""
    import numpy as np
    out = []
    for d, a, b, e in zip(diff, so, sm, se):
        if e == 0:
            out.append(1.0 if d == 0 else 0.0)
            continue
        den = (a ** 4 + b ** 4) / (batches - 1)
        dof = (a ** 2 + b ** 2) ** 2 / den if den > 0 else float("inf")
        out.append(t_two_sided(abs(d) / e, max(dof, 1.0)))
    return np.array(out)


def agreement(scene_path, scene, name, ours, theirs, spp, batches, lines, pvalues):
    import numpy as np
    imgs_o, imgs_m, ids = [], [], None
    for k in range(batches):
        img, _, ids_k = ours.render(scene_path, spp, seed=101 + k, aovs=k == 0)
        imgs_o.append(img)
        ids = ids_k if k == 0 else ids
        imgs_m.append(theirs.render(scene_path, spp, seed=101 + k)[0])
    h, w = imgs_o[0].shape[:2]
    if not geometry(scene_path, ids, theirs, lines):
        failed_geometry = ["geometry"]
    else:
        failed_geometry = []
    ids = ids["id"]
    lines += [f"Agreement: {batches} images of {spp} spp each with independent seeds; per region the mean of "
              "R, G, B (shown: their average) ± the standard error of the mean over the images; |z| is the "
              "largest of the three channels' |difference| / its standard error.", "",
              "| region | pixels | komplex | Mitsuba | max abs z | agree (3 SE) |", "|---|---|---|---|---|---|"]
    worst, failed = 0.0, []
    for rname, m in regions(scene, name, ids, h, w):
        mo = np.array([img[m].mean(axis=0) for img in imgs_o])  # batches x 3
        mm = np.array([img[m].mean(axis=0) for img in imgs_m])
        so, sm = mo.std(axis=0, ddof=1) / np.sqrt(batches), mm.std(axis=0, ddof=1) / np.sqrt(batches)
        diff = mo.mean(axis=0) - mm.mean(axis=0)
        # A region without noise (a mirror of a constant sky) still differs by the rounding of
        # 32-bit floats (both renderers' images): 1e-5 of its value is allowed for that.
        se = np.sqrt(so ** 2 + sm ** 2 + (1e-5 * np.abs(mm.mean(axis=0))) ** 2)
        z = np.where(se > 0, np.abs(diff) / np.maximum(se, 1e-300), np.where(np.abs(diff) > 0, np.inf, 0.0))
        pvalues += [(f"{name}: {rname}", p) for p in welch_p(diff, so, sm, se, batches)]
        ok = bool((z <= 3).all())
        worst = max(worst, float(z.max()))
        if not ok:
            failed.append(rname)
        lines.append(f"| {rname} | {int(m.sum())} | {fmt(mo.mean(), np.sqrt((so ** 2).sum()) / 3)} | "
                     f"{fmt(mm.mean(), np.sqrt((sm ** 2).sum()) / 3)} | {z.max():.2f} | {'yes' if ok else '**no**'} |")
    lines += ["", f"Largest |z|: {worst:.2f}; regions outside 3 SE: {', '.join(failed) if failed else 'none'}.", ""]
    return failed_geometry + failed


def time_error(scene_path, ours, theirs, spp_list, ref_spp, repeats, lines, plot_data):
    import numpy as np
    ref_o = ours.render(scene_path, ref_spp, seed=7)[0]
    ref_m = theirs.render(scene_path, ref_spp, seed=7)[0]
    ref = (ref_o + ref_m) / 2
    # If both are unbiased, (ref_o - ref_m)/2 has the variance of the reference's own noise,
    # which every image's squared error against it contains: it is subtracted.
    ref_mse = float(np.mean(((ref_o - ref_m) / 2) ** 2))
    rows, pts_o, pts_m = [], [], []
    for spp in spp_list:
        # `repeats` images with independent seeds, the two renderers alternating: the mean squared
        # error over them (one image's is dominated by a few bright outliers in a caustic) and the
        # median time (a shared machine).
        t_o, t_m, mse_o, mse_m = [], [], [], []
        for k in range(repeats):
            img, t, _ = ours.render(scene_path, spp, seed=1000 + 17 * spp + k)
            t_o.append(t)
            mse_o.append(np.mean((img - ref) ** 2))
            img, t = theirs.render(scene_path, spp, seed=1000 + 17 * spp + k)
            t_m.append(t)
            mse_m.append(np.mean((img - ref) ** 2))
        t_o, t_m = float(np.median(t_o)), float(np.median(t_m))
        e_o, e_m = [float(np.sqrt(max(np.mean(m) - ref_mse, 0.0))) for m in (mse_o, mse_m)]
        rows.append((spp, t_o, e_o, t_m, e_m))
        pts_o.append((t_o, e_o))
        pts_m.append((t_m, e_m))
    lines += [f"Time against error: RMSE over all pixels and R, G, B against the mean of both renderers at "
              f"{ref_spp} spp, the mean squared error of {repeats} images with independent seeds less the "
              f"reference's own (RMSE {np.sqrt(ref_mse):.4f}, from the difference of its two halves); the "
              "median time. The last column is the time komplex needs for Mitsuba's error, over Mitsuba's "
              "time: `(t·RMSE²)` komplex / `(t·RMSE²)` Mitsuba (the error falls as time^-1/2).", "",
              "| spp | komplex time | komplex RMSE | Mitsuba time | Mitsuba RMSE | time at equal error, komplex / Mitsuba |",
              "|---|---|---|---|---|---|"]
    for s, to, eo, tm, em in rows:
        ratio = (to * eo ** 2) / (tm * em ** 2) if tm * em > 0 else float("nan")
        lines.append(f"| {s} | {to:.3f} s | {eo:.4f} | {tm:.3f} s | {em:.4f} | {ratio:.2f} |")
    s, to, eo, tm, em = rows[-1]
    lines += ["", f"To reach RMSE {em:.4f} (Mitsuba at {s} spp): Mitsuba {tm:.2f} s, komplex "
              f"{to * eo ** 2 / em ** 2:.2f} s (from its time and error at {s} spp).", ""]
    plot_data.append((Path(scene_path).stem, pts_o, pts_m))


def plot(path, data):
    import matplotlib
    import matplotlib.ticker
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(data), figsize=(5 * len(data), 4), squeeze=False)
    for ax, (name, po, pm) in zip(axes[0], data):
        for pts, label, style in ((po, "komplex", "o-"), (pm, "Mitsuba 3 scalar_rgb", "s--")):
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], style, label=label)
        ax.set_title(name)
        ax.xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
        ax.yaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel("wall-clock time (s)")
        ax.set_ylabel("RMSE against the reference")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def machine():
    model = next((ln.split(":", 1)[1].strip() for ln in run(["lscpu"]).splitlines() if "Model name" in ln), "?")
    try:
        commit = run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"])
        dirty = run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"])
    except (subprocess.CalledProcessError, FileNotFoundError):
        commit, dirty = "?", ""
    return f"commit `{commit}`{' (with local changes)' if dirty else ''}, {run(['nproc'])} cores ({model}), " \
           f"load average {os.getloadavg()[0]:.2f} at the start, Python {platform.python_version()}"


def main():
    ensure_venv()
    import mitsuba as mi
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="*", default=[str(ROOT / "scenes/cornell.json"), str(ROOT / "scenes/caustics.json"),
                                                  str(HERE / "scenes/lights-and-lens.json")])
    ap.add_argument("--komplex", default=str(ROOT / "target/release/komplex"), help="the komplex binary")
    ap.add_argument("--width", type=int, default=128)
    ap.add_argument("--height", type=int, help="default: the scene's aspect ratio")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--check-spp", type=int, default=32, help="samples per pixel of each agreement image")
    ap.add_argument("--batches", type=int, default=16, help="independent images per renderer for the agreement")
    ap.add_argument("--repeats", type=int, default=3, help="timed images per renderer and sample count")
    ap.add_argument("--spp", type=int, nargs="+", default=[4, 16, 64, 256], help="sample counts timed")
    ap.add_argument("--ref-spp", type=int, default=2048, help="samples per pixel of each reference")
    ap.add_argument("--skip-agreement", action="store_true")
    ap.add_argument("--skip-timing", action="store_true")
    ap.add_argument("--out", default=str(ROOT / "target/mitsuba/report.md"))
    ap.add_argument("--plot", help="write a PNG of RMSE against time here")
    ap.add_argument("--familywise", type=float, metavar="ALPHA",
                    help="fail only when some region's difference is significant at family-wise level ALPHA "
                         "(Welch's t per channel, Sidak's correction over every comparison), instead of "
                         "at 3 standard errors: the gate .ci/run uses")
    a = ap.parse_args()
    if not Path(a.komplex).exists():
        sys.exit(f"{a.komplex} not found: run `cargo build --release` first (or pass --komplex)")
    sys.path.insert(0, str(HERE))
    from to_mitsuba import scene_size
    lines = ["## Mitsuba 3 cross-check", "",
             f"`python3 scripts/mitsuba/compare.py {' '.join(sys.argv[1:])}`".replace("  ", " "), "",
             f"Machine: {machine()}; Mitsuba {mi.__version__} `scalar_rgb`.", ""]
    failed, plot_data, shown, pvalues = [], [], 0, []
    with tempfile.TemporaryDirectory() as tmp:
        for scene_path in a.scenes:
            with open(scene_path) as f:
                scene = json.load(f)
            w, h = scene_size(scene, a.width, a.height)
            ours = Komplex(a.komplex, a.threads, w, h, tmp)
            theirs = Mitsuba(a.threads, w, h)
            name = Path(scene_path).stem
            lines += [f"### {name} ({w}×{h}, {a.threads} threads; Mitsuba's thread pool: {theirs.threads})", ""]
            if not a.skip_agreement:
                failed += [f"{name}: {r}" for r in
                           agreement(scene_path, scene, name, ours, theirs, a.check_spp, a.batches, lines, pvalues)]
            if not a.skip_timing:
                time_error(scene_path, ours, theirs, a.spp, a.ref_spp, a.repeats, lines, plot_data)
            print("\n".join(lines[shown:]), file=sys.stderr)
            shown = len(lines)
    if a.familywise is not None and pvalues:
        level = 1.0 - (1.0 - a.familywise) ** (1.0 / len(pvalues))
        region, p = min(pvalues, key=lambda rp: rp[1])
        significant = sorted({r for r, q in pvalues if q < level})
        lines += [f"Family-wise test: {len(pvalues)} comparisons, each at {level:.2e} (family-wise {a.familywise}); "
                  f"smallest p-value {p:.2e} ({region}); significant: {', '.join(significant) or 'none'}.", ""]
        failed = [r for r in failed if r.endswith("geometry")] + significant
    lines.append(f"Load average at the end: {os.getloadavg()[0]:.2f}.")
    report = "\n".join(lines) + "\n"
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(report)
    print(report)
    if a.plot and plot_data:
        plot(a.plot, plot_data)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
