#!/usr/bin/env python3
"""check.py KOMPLEX SCENE WORKDIR [WIDTH HEIGHT]: checks the Kubernetes manifests beside
this file without a cluster (docs/cluster.md). First what must agree
between them: the render Job is an Indexed Job whose N completions match
its `--tile auto/N`, it passes --resume, the merge Job lists exactly the N
parts the render writes (komplex's tile names) and writes the render's
output, and both mount the claim of volume.yaml, which is ReadWriteMany.
Then it runs the containers' commands here, as Kubernetes would: each
volume a folder of WORKDIR (the ConfigMap's holding SCENE as scene.json),
the render command once for each index in JOB_COMPLETION_INDEX, then the
merge command, and compares the merged image with a one-process render of
SCENE (scripts/slurm/compare_exr.py). WIDTH and HEIGHT replace the scene's
image size in the ConfigMap's copy (a small image keeps the check fast).
Exits 1 naming the first problem."""
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import yaml

HERE = Path(__file__).resolve().parent
COMPARE = HERE.parent / "slurm" / "compare_exr.py"


class Problem(Exception):
    pass


def need(condition, message):
    if not condition:
        raise Problem(message)


def load(name):
    docs = list(yaml.safe_load_all((HERE / name).read_text()))
    need(len(docs) == 1, f"{name}: {len(docs)} documents, expected 1")
    return docs[0]


def container(job, name):
    need(job.get("apiVersion") == "batch/v1" and job.get("kind") == "Job", f"{name}: not a batch/v1 Job")
    pod = job["spec"]["template"]["spec"]
    need(pod.get("restartPolicy") in ("Never", "OnFailure"), f"{name}: a Job's restartPolicy is Never or OnFailure")
    need(len(pod["containers"]) == 1, f"{name}: one container expected")
    volumes = {}
    for v in pod["volumes"]:
        if "configMap" in v:
            volumes[v["name"]] = ("configMap", v["configMap"]["name"])
        elif "persistentVolumeClaim" in v:
            volumes[v["name"]] = ("claim", v["persistentVolumeClaim"]["claimName"])
        else:
            raise Problem(f"{name}: volume {v['name']} is neither a ConfigMap nor a claim")
    c = pod["containers"][0]
    mounts = {}
    for m in c["volumeMounts"]:
        need(m["name"] in volumes, f"{name}: mount of an undeclared volume {m['name']}")
        mounts[m["mountPath"]] = volumes[m["name"]]
    need(c["command"][0] == "komplex", f"{name}: the command is not komplex")
    return c, mounts


def option(command, flag, name):
    need(command.count(flag) == 1, f"{name}: {flag} should appear once in the command")
    return command[command.index(flag) + 1]


def tile_name(out, i, n):
    # komplex's part names: .tile-I-of-N before the extension.
    p = Path(out)
    return str(p.with_name(f"{p.stem}.tile-{i}-of-{n}{p.suffix}"))


def check_manifests():
    volume = load("volume.yaml")
    need(volume.get("kind") == "PersistentVolumeClaim", "volume.yaml: not a PersistentVolumeClaim")
    need("ReadWriteMany" in volume["spec"]["accessModes"], "volume.yaml: the claim must be ReadWriteMany (pods on several nodes)")
    claim = volume["metadata"]["name"]

    render = load("render-job.yaml")
    spec = render["spec"]
    need(spec.get("completionMode") == "Indexed", "render-job.yaml: completionMode must be Indexed")
    n = spec["completions"]
    need(isinstance(n, int) and n >= 1, "render-job.yaml: completions must be a positive integer")
    need(1 <= spec.get("parallelism", 1) <= n, "render-job.yaml: parallelism must be between 1 and completions")
    rc, rmounts = container(render, "render-job.yaml")
    rcmd = [str(a) for a in rc["command"]]
    need(rcmd[1] == "render", "render-job.yaml: the command is not komplex render")
    need(option(rcmd, "--tile", "render-job.yaml") == f"auto/{n}", f"render-job.yaml: --tile must be auto/{n} (completions)")
    need("--resume" in rcmd, "render-job.yaml: --resume is missing (a retried pod would render its tile again)")
    out = option(rcmd, "-o", "render-job.yaml")

    merge = load("merge-job.yaml")
    need("completionMode" not in merge["spec"] or merge["spec"]["completionMode"] == "NonIndexed", "merge-job.yaml: one pod, not indexed")
    mc, mmounts = container(merge, "merge-job.yaml")
    mcmd = [str(a) for a in mc["command"]]
    need(mcmd[1] == "merge", "merge-job.yaml: the command is not komplex merge")
    need(option(mcmd, "-o", "merge-job.yaml") == out, f"merge-job.yaml: -o must be the render's {out}")
    parts = [a for a in mcmd[2:] if a not in ("-o", out)]
    expected = [tile_name(out, i, n) for i in range(n)]
    need(parts == expected, f"merge-job.yaml: the parts should be {expected}, not {parts}")

    for name, mounts in (("render-job.yaml", rmounts), ("merge-job.yaml", mmounts)):
        claims = [path for path, (kind, what) in mounts.items() if kind == "claim" and what == claim]
        need(claims and out.startswith(claims[0] + "/"), f"{name}: {out} is not on the claim {claim}")
    return n, (rc, rmounts), (mc, mmounts)


def run(komplex, scene, work, n, render, merge, size):
    if work.exists():
        shutil.rmtree(work)
    folders = {}

    def local(arg, mounts):
        for path, (kind, what) in mounts.items():
            if arg == path or arg.startswith(path + "/"):
                folder = work / f"{kind}-{what}"
                if folder not in folders.values():
                    folder.mkdir(parents=True)
                    if kind == "configMap":
                        shutil.copy(scene, folder / "scene.json")
                        if size:
                            doc = json.loads(scene.read_text())
                            doc["camera"]["width"], doc["camera"]["height"] = size
                            (folder / "scene.json").write_text(json.dumps(doc))
                folders[path] = folder
                return str(folder) + arg[len(path):]
        return arg

    env = {k: v for k, v in os.environ.items() if not k.startswith("SLURM_")}
    for c, mounts in (render, merge):
        for path in mounts:
            local(path, mounts)
    for i in range(n):
        c, mounts = render
        cmd = [komplex] + [local(a, mounts) for a in map(str, c["command"][1:])]
        cwd = local(c.get("workingDir", str(work)), mounts)
        subprocess.run(cmd, cwd=cwd, env=dict(env, JOB_COMPLETION_INDEX=str(i)), check=True,
                       stderr=subprocess.DEVNULL)
    c, mounts = merge
    merged = [local(a, mounts) for a in map(str, c["command"][1:])]
    subprocess.run([komplex] + merged, env=env, check=True)
    whole = work / "whole.exr"
    resized = ["--width", str(size[0]), "--height", str(size[1])] if size else []
    subprocess.run([komplex, "render", str(scene), "-o", str(whole)] + resized, env=env, check=True,
                   stderr=subprocess.DEVNULL)
    out = merged[merged.index("-o") + 1]
    subprocess.run([sys.executable, str(COMPARE), out, str(whole)], check=True)


def main():
    if len(sys.argv) not in (4, 6):
        print("usage: scripts/k8s/check.py KOMPLEX SCENE WORKDIR [WIDTH HEIGHT]", file=sys.stderr)
        return 2
    komplex, scene, work = os.path.abspath(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3]).resolve()
    size = tuple(int(v) for v in sys.argv[4:6])
    try:
        n, render, merge = check_manifests()
        run(komplex, scene, work, n, render, merge, size)
    except Problem as e:
        print(f"scripts/k8s/check.py: {e}", file=sys.stderr)
        return 1
    except subprocess.CalledProcessError as e:
        print(f"scripts/k8s/check.py: {' '.join(e.cmd)} failed with status {e.returncode}", file=sys.stderr)
        return 1
    print(f"scripts/k8s: the manifests agree, and their commands render {n} tiles that merge into the one-process image")
    return 0


if __name__ == "__main__":
    sys.exit(main())
