#!/usr/bin/env bash
# The gather step of a render spread over a cluster: merges DPM_FILM_DIR/shard-0.film ...
# shard-(K−1).film (deploy/render-shard.sh's) into one image and one film with
# `dpm merge --expect K·N`, so a lost shard, or one killed after some of its passes, fails
# the merge (exit 2, naming the shards and passes missing) instead of passing as a render
# with fewer passes.
#
#   merge-shards.sh
#
# DPM_TASKS            K, the number of shards (required)
# DPM_FILM_DIR         the directory the shards wrote (required)
# DPM_PASSES_PER_TASK  N, as the shards had it (default 1)
# DPM_OUTPUT           merged image (default DPM_FILM_DIR/merged.exr)
# DPM_MERGED_FILM      merged film (default DPM_FILM_DIR/merged.film)
# DPM_BIN              the dpm binary (default: dpm on PATH)
set -euo pipefail
# shellcheck source=deploy/settings.sh
source "$(dirname "${BASH_SOURCE[0]}")/settings.sh"

[ $# -eq 0 ] || fail "takes no arguments (settings are DPM_* variables)"
: "${DPM_PASSES_PER_TASK:=1}"
need_count DPM_PASSES_PER_TASK
need_count DPM_TASKS
need_dir DPM_FILM_DIR "the shared directory for films"
films=()
for ((i = 0; i < DPM_TASKS; i++)); do
  film=$DPM_FILM_DIR/shard-$i.film
  if [ -f "$film" ]; then
    films+=("$film")
  else
    passes=$(passes_text $((i * DPM_PASSES_PER_TASK)) "$DPM_PASSES_PER_TASK")
    echo "merge-shards.sh: $film is missing: rerun shard $i (passes $passes)" >&2
  fi
done
[ "${#films[@]}" -gt 0 ] || fail "no shard film in $DPM_FILM_DIR (all $DPM_TASKS are missing)"
exec "${DPM_BIN:-dpm}" merge "${films[@]}" --expect $((DPM_TASKS * DPM_PASSES_PER_TASK)) \
  -o "${DPM_OUTPUT:-$DPM_FILM_DIR/merged.exr}" \
  --film "${DPM_MERGED_FILM:-$DPM_FILM_DIR/merged.film}"
