#!/usr/bin/env bash
# Submits a render to Slurm (docs/cluster.md): a job array of
# render.sbatch over tiles, frames, or the tiles of each frame, then, for
# tiles, merge.sbatch with --dependency=afterok on the array, so the merge
# runs once every part is written and is cancelled if a part fails. Prints
# the job ids and where their logs go.
set -euo pipefail

usage() {
    cat >&2 <<'USAGE'
usage: scripts/slurm/submit.sh SCENE OUT.exr --tiles N | --frames A..B [--tiles N]
                               [--threads T] [--max-running M] [--logs DIR] [-- komplex render options]

  --tiles N      render N tiles (one array task each), then merge them into OUT.exr
  --frames A..B  render frames A to B (inclusive) into OUT.AAAA.exr ... OUT.BBBB.exr;
                 with --tiles N, N tiles per frame and one merge per frame
  --threads T    cores per task (sbatch --cpus-per-task) and komplex's --threads (default 1)
  --max-running M  at most M render tasks at once (sbatch --array=...%M; default: no limit)
  --logs DIR     where the jobs' logs go (default: OUT.exr's directory/logs)

Environment: KOMPLEX, the komplex binary (default: komplex on PATH); sbatch's own
SBATCH_* variables (SBATCH_PARTITION, SBATCH_TIMELIMIT, SBATCH_ACCOUNT, ...)
apply to both jobs.
USAGE
    exit 2
}

die() {
    echo "submit.sh: $*" >&2
    exit 1
}

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

[ $# -ge 2 ] || usage
scene=$1 out=$2
shift 2
tiles="" frames="" threads=1 logs="" throttle=""
while [ $# -gt 0 ]; do
    case "$1" in
        --tiles) [ $# -ge 2 ] || usage; tiles=$2; shift 2 ;;
        --frames) [ $# -ge 2 ] || usage; frames=$2; shift 2 ;;
        --threads) [ $# -ge 2 ] || usage; threads=$2; shift 2 ;;
        --logs) [ $# -ge 2 ] || usage; logs=$2; shift 2 ;;
        --max-running) [ $# -ge 2 ] || usage; throttle=$2; shift 2 ;;
        --) shift; break ;;
        -h | --help) usage ;;
        *) echo "submit.sh: unknown option '$1'" >&2; usage ;;
    esac
done
[ -n "$tiles" ] || [ -n "$frames" ] || usage
[ -f "$scene" ] || die "no scene file '$scene'"
[[ "$threads" =~ ^[1-9][0-9]*$ ]] || die "--threads must be a positive integer, not '$threads'"
if [ -n "$tiles" ]; then
    [[ "$tiles" =~ ^[1-9][0-9]*$ ]] || die "--tiles must be a positive integer, not '$tiles'"
fi
if [ -n "$throttle" ]; then
    [[ "$throttle" =~ ^[1-9][0-9]*$ ]] || die "--max-running must be a positive integer, not '$throttle'"
    throttle=%$throttle
fi
count=${tiles:-1}
if [ -n "$frames" ]; then
    [[ "$frames" =~ ^([0-9]+)\.\.([0-9]+)$ ]] || die "--frames must be A..B (frame numbers, inclusive), not '$frames'"
    first=$((10#${BASH_REMATCH[1]})) last=$((10#${BASH_REMATCH[2]}))
    [ "$first" -le "$last" ] || die "--frames $frames: the first frame is after the last"
    count=$(((last - first + 1) * ${tiles:-1}))
fi

# The jobs run with the submitter's environment and working directory
# (sbatch's defaults), so relative paths work on a shared file system; the
# binary is made absolute so that it does not depend on the nodes' PATH.
komplex=${KOMPLEX:-komplex}
komplex_path=$(command -v "$komplex") || die "no komplex binary '$komplex' (set KOMPLEX or put komplex on PATH)"
export KOMPLEX
KOMPLEX=$(cd "$(dirname "$komplex_path")" && pwd)/$(basename "$komplex_path")

outdir=$(dirname "$out")
logs=${logs:-$outdir/logs}
mkdir -p "$outdir" "$logs"

select=()
[ -n "$tiles" ] && select+=(--tiles "$tiles")
[ -n "$frames" ] && select+=(--frames "$frames")

render=$(sbatch --parsable --array="0-$((count - 1))$throttle" --cpus-per-task="$threads" \
    --output="$logs/%x-%A_%a.out" \
    "$here/render.sbatch" "$scene" "$out" "${select[@]}" -- "$@")
render=${render%%;*}
echo "render $render: array 0-$((count - 1)), logs $logs/komplex-render-${render}_*.out"

if [ -n "$tiles" ]; then
    merge_array=()
    merge_log="$logs/%x-%j.out" shown="$logs/komplex-merge-<job>.out"
    if [ -n "$frames" ]; then
        merge_array=(--array="0-$((last - first))")
        merge_log="$logs/%x-%A_%a.out" shown="$logs/komplex-merge-<job>_*.out"
    fi
    merge=$(sbatch --parsable "${merge_array[@]}" --dependency="afterok:$render" --kill-on-invalid-dep=yes \
        --output="$merge_log" \
        "$here/merge.sbatch" "$out" "${select[@]}")
    merge=${merge%%;*}
    echo "merge $merge: after $render succeeds, logs ${shown/<job>/$merge}"
fi
