#!/usr/bin/env bash
# The cluster check of .ci/run (docs/cluster.md). First the Kubernetes
# manifests: scripts/k8s/check.py checks that they agree and runs their
# commands here. Then Slurm: brings up a one-node Slurm
# cluster (one-node.sh), submits a four-tile render array and its merge
# with submit.sh, and compares the merged image with the one-process render
# of the same scene, channel for channel and bit for bit (compare_exr.py,
# with the OpenEXR package). Then deletes one tile and the merged image,
# submits again, and checks that only the missing tile is rendered again
# (--resume) and that the new merge is the same image. Stops the daemons
# and cancels its jobs however it ends. Needs root, apt-get (or Slurm and
# munge installed) and Python's OpenEXR and numpy.
# $KOMPLEX is the binary to check (default: cargo build, target/debug/komplex).
set -euo pipefail
cd "$(dirname "$0")/../.."
start=$SECONDS

slurm=scripts/slurm
dir=target/slurm-check
scene=scenes/table.json
# 70 rows in 4 tiles: 17, 18, 17 and 18 rows (uneven parts).
size=(--width 96 --height 70 --spp 4)
timeout=${SLURM_CHECK_TIMEOUT:-180}

if [ -z "${KOMPLEX:-}" ]; then
    cargo build --quiet --bin komplex
    KOMPLEX=target/debug/komplex
fi
export KOMPLEX

jobs=()
cleanup() {
    if [ ${#jobs[@]} -gt 0 ]; then
        scancel "${jobs[@]}" 2>/dev/null || true
    fi
    "$slurm/one-node.sh" down >/dev/null || echo "check.sh: one-node.sh down failed" >&2
}
trap cleanup EXIT
trap 'exit 130' INT TERM

fail() {
    {
        echo "check.sh: $*"
        if [ ${#jobs[@]} -gt 0 ]; then
            echo "--- jobs"
            for job in "${jobs[@]}"; do scontrol show job -o "$job" 2>/dev/null || true; done \
                | grep -oE '^JobId=[^ ]+|ArrayTaskId=[^ ]+|JobName=[^ ]+|JobState=[^ ]+|Reason=[^ ]+|ExitCode=[^ ]+' \
                | paste -sd ' ' | sed 's/ JobId=/\nJobId=/g' || true
        fi
        for log in "$dir"/logs/*.out; do
            [ -e "$log" ] || continue
            echo "--- $log"
            cat "$log"
        done
    } >&2
    exit 1
}

# Submits the four tiles and the merge; waits until both jobs have left the
# queue and checks that every task completed.
submit_and_wait() {
    local out render merge
    out=$("$slurm/submit.sh" "$scene" "$dir/img.exr" --tiles 4 -- "${size[@]}") || fail "submit.sh failed"
    echo "$out"
    render=$(awk '$1 == "render" { print $2 }' <<<"$out" | tr -d :)
    merge=$(awk '$1 == "merge" { print $2 }' <<<"$out" | tr -d :)
    if [ -z "$render" ] || [ -z "$merge" ]; then fail "no job ids in submit.sh's output"; fi
    jobs=("$render" "$merge")
    local deadline=$((SECONDS + timeout))
    while [ -n "$(squeue -h -j "$render,$merge" -o %i 2>/dev/null)" ]; do
        [ "$SECONDS" -lt "$deadline" ] || fail "the jobs are still queued or running after $timeout s"
        # A task that cannot start (a full disk, say) drains the node and is
        # held: fail now rather than at the time-out.
        case "$(sinfo -h -o %T 2>/dev/null)" in
            drain* | down* | fail*) fail "the node is $(sinfo -h -o %T): $(sinfo -h -R -o %E)" ;;
        esac
        sleep 0.5
    done
    local done_render done_merge
    done_render=$(scontrol show job -o "$render" | grep -c 'JobState=COMPLETED' || true)
    done_merge=$(scontrol show job -o "$merge" | grep -c 'JobState=COMPLETED' || true)
    [ "$done_render" -eq 4 ] || fail "not every task completed ($done_render of 4 render tasks, $done_merge of 1 merge)"
    [ "$done_merge" -eq 1 ] || fail "not every task completed ($done_render of 4 render tasks, $done_merge of 1 merge)"
    jobs=()
}

rm -rf "$dir"
mkdir -p "$dir"

echo "cluster check: the Kubernetes manifests agree with each other and their commands, run here, give the one-process image"
python3 -c 'import yaml' 2>/dev/null \
    || python3 -m pip install --quiet --disable-pip-version-check PyYAML==6.0.3
python3 scripts/k8s/check.py "$KOMPLEX" "$scene" "$dir/k8s" 96 70
echo "cluster check: $((SECONDS - start)) s so far"

echo "cluster check: bringing up the one-node Slurm cluster"
"$slurm/one-node.sh" up
echo "cluster check: $((SECONDS - start)) s so far"
submit_and_wait
"$KOMPLEX" render "$scene" "${size[@]}" -o "$dir/whole.exr" 2>/dev/null
python3 "$slurm/compare_exr.py" "$dir/img.exr" "$dir/whole.exr" || fail "the merged image differs from the one-process render"
echo "cluster check: $((SECONDS - start)) s so far"

echo "cluster check: resubmitting with tile 2 and the merged image deleted (--resume renders only tile 2)"
tile() { echo "$dir/img.tile-$1-of-4.exr"; }
before=$(stat -c '%n %i %Y' "$(tile 0)" "$(tile 1)" "$(tile 3)")
rm "$(tile 2)" "$dir/img.exr"
submit_and_wait
after=$(stat -c '%n %i %Y' "$(tile 0)" "$(tile 1)" "$(tile 3)")
[ "$before" = "$after" ] || fail "--resume rewrote tiles that were complete:"$'\n'"$before"$'\n'"$after"
python3 "$slurm/compare_exr.py" "$dir/img.exr" "$dir/whole.exr" || fail "the merged image differs from the one-process render"

echo "cluster check passed in $((SECONDS - start)) s"
