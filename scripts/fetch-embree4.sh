#!/usr/bin/env bash
# Fetches Embree 4.4.0 for dpm's `embree4` feature: Debian 12 packages no Embree 4, so this takes
# the two shared libraries out of the PyPI wheel embreex==4.4.0.post1 (manylinux_2_28, x86_64):
# libembree4-4aef3270.so.4 (its SONAME; RPATH $ORIGIN) and the libtbb-dcf63f8c.so.12 it needs,
# and adds the libembree4.so link the linker looks for.
#
#   scripts/fetch-embree4.sh [DIR]      DIR defaults to target/embree4 (where build.rs looks)
#
# Needs python3 with pip (Debian: apt-get install -y python3-pip); `pip download` installs
# nothing. Running it again over a complete DIR does nothing; `cargo clean` removes the default
# DIR (it lies in target/), so fetch again after one.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
DIR=${1:-$repo/target/embree4}
WHEEL_VERSION=4.4.0.post1
LIB=libembree4-4aef3270.so.4
TBB=libtbb-dcf63f8c.so.12

if [ ! -e "$DIR/libembree4.so" ] || [ ! -e "$DIR/$LIB" ] || [ ! -e "$DIR/$TBB" ]; then
  mkdir -p "$DIR"
  download=$(mktemp -d)
  trap 'rm -rf "$download"' EXIT
  python3 -m pip download --quiet --no-deps --only-binary=:all: \
    --platform manylinux_2_28_x86_64 --python-version 3.11 --implementation cp \
    "embreex==$WHEEL_VERSION" -d "$download"
  wheel=$(ls "$download"/embreex-"$WHEEL_VERSION"-*.whl)
  python3 - "$wheel" "$DIR" "$LIB" "$TBB" <<'PY'
import os, shutil, sys, zipfile
wheel, out, *names = sys.argv[1:]
with zipfile.ZipFile(wheel) as z:
    for name in names:
        with z.open("embreex.libs/" + name) as src, open(os.path.join(out, name), "wb") as dst:
            shutil.copyfileobj(src, dst)
        os.chmod(os.path.join(out, name), 0o755)
PY
  ln -sfn "$LIB" "$DIR/libembree4.so"
fi

abs=$(cd "$DIR" && pwd)
echo "Embree 4.4.0 is in $abs"
if [ "$abs" = "$repo/target/embree4" ]; then
  echo "build and run with:  cargo build --release --features embree4"
else
  echo "build and run with:  EMBREE4_DIR=$abs cargo build --release --features embree4"
fi
echo "(target/release/dpm then finds the library through its rpath; dpm --version names it)"
