#!/usr/bin/env bash
# Renders the torus knot and the Cornell box with both Embree backends, the same seed and
# settings, at small sizes, and checks that the images agree within noise: relative MSE
# Σ(a − b)² / Σ b² ≤ 1e-3 (examples/compare_images.rs), Embree 3's image as the reference.
# Needs Embree 4 fetched first (scripts/fetch-embree4.sh; EMBREE4_DIR is honoured). The two
# binaries and the images are kept in target/backends/.
#
#   scripts/compare-backends.sh          (about a minute of rendering on 2 cores, plus builds)
set -euo pipefail
cd "$(dirname "$0")/.."
out=target/backends
mkdir -p "$out"
ln -sfn "$(pwd)/scenes/meshes" "$out/meshes"

cargo build --release --bin dpm --example compare_images
cp target/release/dpm "$out/dpm-embree3"
cp target/release/examples/compare_images "$out/compare_images"
cargo build --release --features embree4 --bin dpm
cp target/release/dpm "$out/dpm-embree4"

# name, scene, resolution, render flags
cases=(
  "torus-knot|scenes/torus-knot.toml|200, 150|--caustic-photons 200000"
  "cornell-box|scenes/cornell-box.toml|96, 96|--caustic-photons 50000 --global-photons 50000 --final-gather 8"
)
status=0
for case in "${cases[@]}"; do
  IFS='|' read -r name scene resolution flags <<<"$case"
  sed "s/^resolution = .*/resolution = [$resolution]/" "$scene" >"$out/$name.toml"
  for backend in embree3 embree4; do
    # shellcheck disable=SC2086 # the flags are words
    "$out/dpm-$backend" render "$out/$name.toml" --seed 1 $flags \
      -o "$out/$name-$backend.pfm" 2>"$out/$name-$backend.log"
    echo "$name: $("$out/dpm-$backend" --version) rendered in $(awk '/^total/ {print $2}' "$out/$name-$backend.log") s"
  done
  printf '%s: ' "$name"
  "$out/compare_images" "$out/$name-embree4.pfm" "$out/$name-embree3.pfm" 1e-3 || status=1
done
# Leave target/release/dpm as the default (Embree 3) build, as `cargo build --release` would.
cargo build --release --bin dpm
exit $status
