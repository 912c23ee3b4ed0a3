#!/usr/bin/env bash
# Submits a render spread over a Slurm cluster: the array of DPM_TASKS shards
# (render.sbatch, --array=0-(K−1)) and the merge job (merge.sbatch) that starts once every
# task has succeeded (--dependency=afterok; --kill-on-invalid-dep cancels it when a task
# fails, instead of leaving it pending for ever). Prints "ARRAY_JOB_ID MERGE_JOB_ID".
# Arguments go to both sbatch calls (--partition, --account, --output, --cpus-per-task ...).
#
#   DPM_BIN=/shared/bin/dpm DPM_SCENE=/shared/scenes/box.toml DPM_FILM_DIR=/shared/films \
#   DPM_TASKS=16 DPM_PASSES_PER_TASK=4 deploy/slurm/submit.sh --partition=cpu
#
# The other settings (DPM_RENDER_ARGS, DPM_THREADS, DPM_OUTPUT ...) are described in
# deploy/render-shard.sh and deploy/merge-shards.sh; sbatch passes the environment on.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source=deploy/settings.sh
source "$here/../settings.sh"
export DPM_DEPLOY_DIR=${DPM_DEPLOY_DIR:-$(dirname "$here")}

# Checked here too, so a typo fails now and not in K queued tasks.
: "${DPM_PASSES_PER_TASK:=1}"
need_count DPM_PASSES_PER_TASK
need_count DPM_TASKS
need_dir DPM_FILM_DIR "the shared directory for films"
[ -f "${DPM_SCENE:-}" ] || fail "DPM_SCENE '${DPM_SCENE:-}' is not a scene file"
export DPM_PASSES_PER_TASK DPM_TASKS

array=$(sbatch --parsable --array=0-$((DPM_TASKS - 1)) "$@" "$here/render.sbatch")
array=${array%%;*} # --parsable prints "id" or "id;cluster"
merge=$(sbatch --parsable --dependency=afterok:"$array" --kill-on-invalid-dep=yes "$@" \
  "$here/merge.sbatch")
echo "$array ${merge%%;*}"
