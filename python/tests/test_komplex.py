"""The Python module against the command line (the same Rust results) and
against independent checks (analytic shapes, membership sampled along rays).

Run from the repository root after `pip install ./python`:
`python -m pytest python/tests`. The command-line binary is
`$KOMPLEX_BIN`, else `target/debug/komplex` (built by `cargo build` if missing).
"""
import json
import math
import os
import subprocess
import threading
from pathlib import Path

import numpy as np
import pytest

import komplex

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"

BALLS = """{
  "camera": {"eye": [0, 0, 8], "direction": [0, 0, -1], "width": 40, "height": 30},
  "lights": [{"position": [3, 4, 8]}],
  "materials": {"red": {"diffuse": [1, 0, 0]}, "glass": {"transmit": [0.9, 0.9, 0.9], "ior": 1.5}},
  "blocks": [
    {"name": "ball", "material": "red", "objects": [{"sphere": {"radius": 1.5}}]},
    {"name": "lens", "material": "glass", "transparent": true,
     "objects": [{"sphere": {"radius": 2}, "transform": [{"translate": [1.5, 0, 0]}]}]},
    {"name": "post", "material": "red",
     "objects": [{"cylinder": {"radius": 0.5}, "transform": [{"translate": [-4, 0, 0]}]},
                 {"halfspace": [0, 1, 0, -1]}, {"halfspace": [0, -1, 0, -1]}]}
  ]
}"""


@pytest.fixture(scope="session")
def cli():
    """The komplex binary, for comparing with the command line."""
    path = Path(os.environ.get("KOMPLEX_BIN", ROOT / "target" / "debug" / "komplex"))
    if not path.exists():
        subprocess.run(["cargo", "build", "-q", "--bin", "komplex"], cwd=ROOT, check=True)
    return path


@pytest.fixture(scope="session")
def balls():
    return komplex.loads(BALLS)


def owner_of(p):
    """The owner by membership and the priority rule (docs/model.md §3.4),
    written out for BALLS: opaque ball, then post, then the transparent lens."""
    x, y, z = p
    if x * x + y * y + z * z <= 1.5**2:
        return 1
    if (x + 4) ** 2 + z * z <= 0.25 and -1 <= y <= 1:
        return 3
    if (x - 1.5) ** 2 + y * y + z * z <= 4:
        return 2
    return 0


def near_a_surface(p, d=1e-6):
    return any(owner_of(p + e) != owner_of(p) for e in d * np.vstack([np.eye(3), -np.eye(3)]))


def test_load_and_blocks():
    scene = komplex.load(SCENES / "primitives.json")
    assert len(scene) == 10
    blocks = scene.blocks
    assert [b["index"] for b in blocks] == list(range(1, 11))
    assert blocks[0]["name"] == "sphere" and blocks[0]["material"] == "red"
    lo, hi = blocks[0]["box"]
    # The unit ball at (-3, 1, -3): its box, to the kernel's slack.
    assert np.allclose(lo, [-4, 0, -4], atol=1e-6) and np.allclose(hi, [-2, 2, -2], atol=1e-6)
    assert not blocks[0]["transparent"]


def test_classify_against_membership(balls):
    rng = np.random.default_rng(7)
    points = rng.uniform(-5, 4, size=(20000, 3))
    owners = balls.classify(points)
    assert owners.dtype == np.uint32 and owners.shape == (20000,)
    checked = 0
    for p, got in zip(points, owners):
        if near_a_surface(p):
            continue
        assert got == owner_of(p), p
        checked += 1
    assert checked > 19000
    assert set(np.unique(owners)) == {0, 1, 2, 3}


def test_classify_accepts_lists_and_other_dtypes(balls):
    assert balls.classify([[0, 0, 0], [9, 9, 9]]).tolist() == [1, 0]
    assert balls.classify(np.array([[0, 0, 0]], dtype=np.float32)).tolist() == [1]
    assert balls.classify(np.zeros((0, 3))).shape == (0,)
    # Not contiguous: every other row of a larger array.
    big = np.zeros((10, 3))
    big[::2, 0] = 10
    assert balls.classify(big[::2]).tolist() == [0] * 5


@pytest.mark.parametrize(
    "bad, needle",
    [
        (np.zeros((4, 2)), "shape (N, 3)"),
        (np.zeros(3), "shape (N, 3)"),
        (np.zeros((2, 3, 1)), "shape (N, 3)"),
        ([["a", "b", "c"]], "array of numbers"),
        (np.array([[0, 0, np.nan]]), "points[0] is not finite"),
        (np.array([[0, 0, 0], [np.inf, 0, 0]]), "points[1] is not finite"),
    ],
)
def test_classify_refuses_bad_points(balls, bad, needle):
    with pytest.raises(ValueError, match=needle.replace("(", r"\(").replace(")", r"\)").replace("[", r"\[").replace("]", r"\]")):
        balls.classify(bad)


def test_rays_refused_with_the_row_named(balls):
    o = np.zeros((3, 3))
    d = np.array([[1.0, 0, 0], [0, 0, 0], [0, 1, 0]])
    with pytest.raises(ValueError, match=r"directions\[1\]"):
        balls.cast(o, d)
    with pytest.raises(ValueError, match="same length"):
        balls.trace(o, d[:2])
    with pytest.raises(ValueError, match="max_t"):
        balls.cast(o[:1], d[:1], max_t=float("nan"))


def test_trace_against_membership_along_each_ray(balls):
    rng = np.random.default_rng(3)
    origins = rng.uniform(-6, 6, size=(300, 3))
    directions = rng.normal(size=(300, 3))
    traces = balls.trace(origins, directions)
    assert len(traces) == 300 and traces.offsets.shape == (301,) and traces.offsets[0] == 0
    unit = directions / np.linalg.norm(directions, axis=1)[:, None]
    for i in range(300):
        a, b = traces.offsets[i], traces.offsets[i + 1]
        start, end, block = traces.start[a:b], traces.end[a:b], traces.block[a:b]
        assert start[0] == 0 and math.isinf(end[-1]) and np.all(start[1:] == end[:-1])
        for s, e, owner in zip(start, end, block):
            e = min(e, s + 50)
            # Membership sampled inside the segment, away from its ends.
            for t in np.linspace(s, e, 7)[1:-1]:
                p = origins[i] + t * unit[i]
                if not near_a_surface(p, 1e-7):
                    assert owner_of(p) == owner, (i, t)


def test_trace_and_cast_equal_the_command_line(balls, cli, tmp_path):
    scene = tmp_path / "balls.json"
    scene.write_text(BALLS)
    rng = np.random.default_rng(11)
    origins = np.vstack([[0, 0.3, 8], [-8, 0.1, 0.2], rng.uniform(-6, 6, size=(6, 3))])
    directions = np.vstack([[0, 0, -1], [1, 0, 0], rng.normal(size=(6, 3))])
    traces = balls.trace(origins, directions)
    hits = balls.cast(origins, directions)
    for i, (o, d) in enumerate(zip(origins, directions)):
        args = [cli, "trace", scene, "--json", "--origin", *(repr(float(x)) for x in o)]
        args += ["--direction", *(repr(float(x)) for x in d)]
        want = json.loads(subprocess.run(list(map(str, args)), capture_output=True, check=True, text=True).stdout)
        a, b = traces.offsets[i], traces.offsets[i + 1]
        got = [
            {"start": s, "end": None if math.isinf(e) else e, "block": int(k) or None}
            for s, e, k in zip(traces.start[a:b], traces.end[a:b], traces.block[a:b])
        ]
        assert got == [{k: seg[k] for k in ("start", "end", "block")} for seg in want["segments"]]
        hit = want["hit"]
        if hit is None:
            assert math.isinf(hits.t[i]) and hits.block[i] == 0 and np.all(np.isnan(hits.point[i]))
        else:
            assert hits.t[i] == hit["t"] and hits.block[i] == hit["block"] and hits.solid[i] == hit["object"]
            assert hits.point[i].tolist() == hit["point"] and hits.normal[i].tolist() == hit["normal"]


def test_cast_against_the_analytic_ball(balls):
    # Rays from far along +z at points of the ball's disc that the lens
    # misses: the ball is hit first, where z = sqrt(r² - x² - y²).
    rng = np.random.default_rng(5)
    xy = rng.uniform(-1.5, 1.5, size=(4000, 2))
    xy = xy[((xy**2).sum(axis=1) < 1.5**2) & ((xy[:, 0] - 1.5) ** 2 + xy[:, 1] ** 2 > 2**2)][:500]
    assert len(xy) == 500
    origins = np.column_stack([xy, np.full(500, 10.0)])
    hits = balls.cast(origins, np.tile([0.0, 0, -1], (500, 1)))
    z = np.sqrt(1.5**2 - (xy**2).sum(axis=1))
    assert np.all(hits.block == 1) and np.all(hits.entering)
    assert np.allclose(hits.t, 10 - z, rtol=0, atol=1e-12)
    assert np.allclose(hits.normal, hits.point / 1.5, atol=1e-12)
    short = balls.cast(origins, np.tile([0.0, 0, -1], (500, 1)), max_t=8.0)
    assert np.all(short.block == 0) and np.all(np.isinf(short.t))


def test_render_equals_the_command_line_exr(cli, tmp_path):
    OpenEXR = pytest.importorskip("OpenEXR")
    scene_path = SCENES / "primitives.json"
    out = tmp_path / "p.exr"
    subprocess.run([str(cli), "render", str(scene_path), "-o", str(out), "--width", "64", "--height", "48"], check=True)
    got = komplex.load(scene_path).render(width=64, height=48)
    with OpenEXR.File(str(out), separate_channels=True) as f:
        channels = f.channels()
        assert set(channels) == set(got)
        for name, channel in channels.items():
            assert got[name].shape == (48, 64)
            assert got[name].dtype == channel.pixels.dtype, name
            assert np.array_equal(got[name], channel.pixels, equal_nan=True), name
    # The scene keeps its own camera afterwards.
    assert komplex.load(scene_path).render(width=8)["R"].shape == (6, 8)


def test_path_render_with_spp_and_noise_equals_the_command_line_exr(cli, tmp_path):
    OpenEXR = pytest.importorskip("OpenEXR")
    scene_path = SCENES / "primitives.json"
    out = tmp_path / "p.exr"
    args = ["--width", "24", "--height", "18", "--spp", "32", "--noise", "0.2", "--seed", "3"]
    subprocess.run([str(cli), "render", str(scene_path), "-o", str(out), *args], check=True)
    got = komplex.load(scene_path).render(width=24, height=18, spp=32, noise=0.2, seed=3)
    assert "spp" in got and "error" in got
    assert got["spp"].min() >= 16 and got["spp"].max() <= 32
    with OpenEXR.File(str(out), separate_channels=True) as f:
        channels = f.channels()
        assert set(channels) == set(got)
        for name, channel in channels.items():
            assert np.array_equal(got[name], channel.pixels, equal_nan=True), name
    # Another seed, another image of the same scene.
    other = komplex.load(scene_path).render(width=24, height=18, spp=32, noise=0.2, seed=4)
    assert not np.array_equal(other["R"], got["R"])
    with pytest.raises(ValueError, match="spp"):
        komplex.load(scene_path).render(spp=0)
    with pytest.raises(ValueError, match="noise"):
        komplex.load(scene_path).render(noise=-1.0)


def test_render_options_checked(balls):
    with pytest.raises(ValueError, match="samples"):
        balls.render(samples=0)
    with pytest.raises(ValueError, match="precision"):
        balls.render(precision="exact")
    image = balls.render(width=20, samples=2, precision="certified", threads=1)
    assert image["id.block"].shape == (15, 20) and image["id.block"][7, 10] == 1
    assert balls.render()["R"].shape == (30, 40)


def test_bad_scene_raises_scene_error_with_the_cli_message(cli, tmp_path):
    text = BALLS.replace('"radius": 1.5', '"radius": -1.5')
    path = tmp_path / "bad.json"
    path.write_text(text)
    with pytest.raises(komplex.SceneError) as from_file:
        komplex.load(path)
    cli_run = subprocess.run([str(cli), "check", str(path)], capture_output=True, text=True)
    assert cli_run.returncode == 1
    assert cli_run.stderr.strip() == f"error: {from_file.value}"
    assert "blocks[0].objects[0]" in str(from_file.value) and "line 6" in str(from_file.value)
    with pytest.raises(komplex.SceneError, match="<string>: .*line 6"):
        komplex.loads(text)
    with pytest.raises(ValueError):
        komplex.loads("{")
    with pytest.raises(FileNotFoundError):
        komplex.load(tmp_path / "missing.json")


def test_queries_from_many_threads_agree(balls):
    rng = np.random.default_rng(1)
    points = rng.uniform(-5, 4, size=(50000, 3))
    want = balls.classify(points)
    results = [None] * 4

    def work(k):
        results[k] = balls.classify(points)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert all(np.array_equal(r, want) for r in results)


def test_volumes_against_analytic_values_and_the_command_line(balls, cli, tmp_path):
    ball, lens, post = 4 / 3 * math.pi * 1.5**3, 4 / 3 * math.pi * 8, math.pi * 0.25 * 2
    # The lens of the ball (r 1.5) and the transparent sphere (r 2), centres 1.5 apart.
    shared = math.pi * (1.5 + 2 - 1.5) ** 2 * (1.5**2 + 2 * 1.5 * 3.5 - 3 * 0.5**2) / (12 * 1.5)
    got = balls.volumes(tolerance=1e-3)
    want_owned = [ball, lens - shared, post]
    want_own = [ball, lens, post]
    for b, owned, own in zip(got["blocks"], want_owned, want_own):
        assert b["bounded"] and abs(b["volume"] - owned) <= 4 * b["error"] + 1e-12, (b, owned)
        assert abs(b["own_volume"] - own) <= 4 * b["own_error"] + 1e-12, (b, own)
    union = got["union"]
    assert abs(union["volume"] - (ball + lens - shared + post)) <= 4 * union["error"]
    scene = tmp_path / "balls.json"
    scene.write_text(BALLS)
    run = subprocess.run([str(cli), "volume", str(scene), "--json", "--tolerance", "1e-3"], capture_output=True, text=True, check=True)
    assert json.loads(run.stdout) == got
    with pytest.raises(ValueError, match="tolerance"):
        balls.volumes(tolerance=0)


def test_overlaps_find_the_lens(balls):
    got = balls.overlaps(tolerance=1e-3)
    assert [(o["a"], o["b"]) for o in got["overlaps"]] == [(1, 2)]
    o = got["overlaps"][0]
    shared = math.pi * 2**2 * (1.5**2 + 2 * 1.5 * 3.5 - 3 * 0.5**2) / (12 * 1.5)
    assert abs(o["volume"] - shared) <= 4 * o["error"]
    x, y, z = o["point"]
    assert x * x + y * y + z * z <= 1.5**2 and (x - 1.5) ** 2 + y * y + z * z <= 4


def test_import_openmc_classifies_points_into_openmc_cells():
    # The README points of OpenMC's lattice test model (tests/openmc/README.md).
    scene = komplex.import_openmc(ROOT / "tests" / "openmc" / "lattice" / "geometry.xml")
    names = [b["name"] for b in scene.blocks]
    points = [[0.01, 0.01, 50], [0.7, 0.01, 50], [21.336, 0.01, 50], [0.72, 0.1, 4.5],
              [0.01, 0.01, 3.3], [0.01, 0.01, -10], [40, 40, 50]]
    owners = scene.classify(points)
    got = [names[k - 1] if k else None for k in owners.tolist()]
    assert got == ["cell 23", "cell 24", "cell 47", "cell 31", "cell 21", "cell 1", None]


def test_import_openmc_errors_name_the_place(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text('<geometry><surface id="1" type="spere" coeffs="0 0 0 1"/></geometry>')
    with pytest.raises(ValueError, match="line 1, column 11: surface 1: unknown surface type `spere`"):
        komplex.import_openmc(bad)
    with pytest.raises(FileNotFoundError):
        komplex.import_openmc(tmp_path / "none.xml")
