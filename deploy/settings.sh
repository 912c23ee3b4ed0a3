# shellcheck shell=bash
# Sourced by the scale-out scripts (render-shard.sh, merge-shards.sh, slurm/submit.sh): the
# checks of the DPM_* settings they share. A bad setting exits 2 naming the variable, before
# any work is queued or done.

fail() {
  echo "${0##*/}: $*" >&2
  exit 2
}

# need_count VAR: $VAR as a whole number ≥ 1, normalised to base 10 ("08" is 8, not an octal
# error). Seven digits at most: dpm caps a render at 1,000,000 passes, and bash arithmetic
# must not wrap.
need_count() {
  local value=${!1:-}
  [[ $value =~ ^0*[1-9][0-9]{0,6}$ ]] || fail "$1 '$value' is not a whole number from 1 up"
  printf -v "$1" '%d' "$((10#$value))"
}

# need_dir VAR WHAT: $VAR names an existing directory.
need_dir() {
  [ -n "${!1:-}" ] || fail "$1 is not set ($2)"
  [ -d "${!1}" ] || fail "$1 ${!1} is not a directory ($2)"
}

# passes_text FIRST COUNT: "4" or "4-7", as dpm names pass ranges.
passes_text() {
  if [ "$2" -eq 1 ]; then echo "$1"; else echo "$1-$(($1 + $2 - 1))"; fi
}
