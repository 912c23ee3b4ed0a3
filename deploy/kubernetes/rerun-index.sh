#!/usr/bin/env bash
# Prints a Job that renders one index of render-job.yaml again, for `kubectl apply -f -`:
# when an index has used up its backoffLimitPerIndex and the render Job has failed, the other
# indexes' films are kept, and this reruns just the lost one (its film comes out the same).
#
#   deploy/kubernetes/rerun-index.sh 3 | kubectl apply -f -
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
[[ ${1:-} =~ ^[0-9]{1,7}$ ]] || {
  echo "usage: rerun-index.sh INDEX (the shard number to render again)" >&2
  exit 2
}
index=$((10#$1))
# One pod with the index written in, under a name of its own.
sed -e "s/^  name: dpm-render\$/  name: dpm-render-$index/" \
  -e "s/\"\$(JOB_COMPLETION_INDEX)\"/\"$index\"/" \
  -e 's/^  completions: .*/  completions: 1/' \
  -e 's/^  parallelism: .*/  parallelism: 1/' \
  "$here/render-job.yaml"
