#!/usr/bin/env bash
# One worker of a render spread over a cluster: shard INDEX renders passes
# [INDEX·N, INDEX·N + N) into DPM_FILM_DIR/shard-INDEX.film (and a preview, shard-INDEX.exr).
# The Slurm array (deploy/slurm/render.sbatch) and the Kubernetes Indexed Job
# (deploy/kubernetes/render-job.yaml) both run exactly this; deploy/merge-shards.sh gathers.
#
#   render-shard.sh INDEX
#
# DPM_SCENE            scene file (required)
# DPM_FILM_DIR         directory every worker and the merge see (required)
# DPM_PASSES_PER_TASK  N, passes per shard (default 1)
# DPM_RENDER_ARGS      more `dpm render` flags, split on spaces; the same for every shard
# DPM_THREADS          worker threads (default SLURM_CPUS_PER_TASK, else 0: one per core)
# DPM_BIN              the dpm binary (default: dpm on PATH)
#
# Pass i depends only on the scene, the settings, the seed and i, so a rerun of INDEX writes
# the same film, byte for byte, and needs nothing from any other shard.
set -euo pipefail
# shellcheck source=deploy/settings.sh
source "$(dirname "${BASH_SOURCE[0]}")/settings.sh"

[ $# -eq 1 ] || fail "usage: render-shard.sh INDEX (got $# arguments)"
[[ $1 =~ ^[0-9]{1,7}$ ]] || fail "INDEX '$1' is not a shard number (0, 1, 2, ...)"
index=$((10#$1))
: "${DPM_PASSES_PER_TASK:=1}"
need_count DPM_PASSES_PER_TASK
need_dir DPM_FILM_DIR "the shared directory for films"
[ -n "${DPM_SCENE:-}" ] || fail "DPM_SCENE is not set (the scene file to render)"
read -r -a extra <<<"${DPM_RENDER_ARGS:-}"
first=$((index * DPM_PASSES_PER_TASK))
film=$DPM_FILM_DIR/shard-$index.film
echo "shard $index: passes $(passes_text "$first" "$DPM_PASSES_PER_TASK") of $DPM_SCENE -> $film" >&2
# exec: the scheduler's signals (scancel, a pod's termination) reach dpm itself.
exec "${DPM_BIN:-dpm}" render "$DPM_SCENE" --first-pass "$first" \
  --passes "$DPM_PASSES_PER_TASK" --threads "${DPM_THREADS:-${SLURM_CPUS_PER_TASK:-0}}" \
  --film "$film" -o "$DPM_FILM_DIR/shard-$index.exr" "${extra[@]}"
