#!/usr/bin/env bash
# Validates the manifests beside this script (and the Job rerun-index.sh makes) offline against Kubernetes' own schemas, strictly
# (an unknown field is an error), with PyPI's kubernetes-validate, which carries the schemas of
# every Kubernetes release it knows. It is installed in a virtual environment under the build
# folder, so the system's Python is left alone. 1.29 is the first release whose Jobs have
# backoffLimitPerIndex on by default; 1.30 is checked too.
#
#   deploy/kubernetes/validate.sh          (needs python3-venv; a few seconds once installed)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
cd "$here/../.."
venv=$(realpath -m "${CARGO_TARGET_DIR:-target}/kubernetes-validate")
if [ ! -x "$venv/bin/kubernetes-validate" ]; then
  python3 -m venv "$venv" || {
    echo "validate.sh: cannot make a Python virtual environment: apt-get install -y python3-venv" >&2
    exit 1
  }
  "$venv/bin/pip" install --quiet kubernetes-validate==1.37.0
fi
# The Job rerun-index.sh makes for a lost index, as docs/scale-out.md has users apply it.
rerun=$(mktemp --suffix=.yaml)
trap 'rm -f "$rerun"' EXIT
"$here/rerun-index.sh" 3 >"$rerun"
if ! grep -q '^  name: dpm-render-3$' "$rerun" || ! grep -q 'args: \["3"\]' "$rerun"; then
  echo "validate.sh: rerun-index.sh 3 did not write index 3 into the Job" >&2
  exit 1
fi
for version in 1.29.0 1.30.0; do
  "$venv/bin/kubernetes-validate" --strict --kubernetes-version "$version" "$here"/*.yaml "$rerun"
done
