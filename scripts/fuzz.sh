#!/usr/bin/env bash
# Runs every fuzz target (fuzz/fuzz_targets) for SECONDS each (default 30) from its committed
# seed corpus, with libFuzzer's bounds: no single allocation over 64 MiB (a size field the file
# merely claims must not be obeyed), 2 GiB in all, 5 s per input. A crash, leak, timeout or
# failed assertion stops the script with libFuzzer's report and the input saved under
# fuzz/artifacts/TARGET/. Uses nightly Rust when rustup has it, otherwise the stable compiler
# with RUSTC_BOOTSTRAP=1 (cargo-fuzz needs -Z flags; stable ships the sanitizer runtimes).
#
#   scripts/fuzz.sh            # 30 s each, as CI runs it
#   scripts/fuzz.sh 1800 pbrt  # one target for 30 minutes
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
seconds=${1:-30}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(ply pbrt scene_toml obj photon_map film image)

if ! cargo fuzz --version >/dev/null 2>&1; then
  cargo install cargo-fuzz --locked --version 0.13.2
fi
if rustup toolchain list 2>/dev/null | grep -q '^nightly'; then
  fuzz=(cargo +nightly fuzz)
else
  export RUSTC_BOOTSTRAP=1
  fuzz=(cargo fuzz)
fi
"${fuzz[@]}" build
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for target in "${targets[@]}"; do
  echo "== fuzzing $target for $seconds s"
  mkdir -p "$work/$target"
  set +e
  "${fuzz[@]}" run "$target" "$work/$target" "corpus/$target" -- \
    -max_total_time="$seconds" -malloc_limit_mb=64 -rss_limit_mb=2048 -timeout=5 \
    -print_final_stats=1 2>&1 | grep -E '^(stat::|Done|INFO: seed corpus|==[0-9]+==|SUMMARY|artifact_prefix|Test unit written|thread .* panicked)'
  status=${PIPESTATUS[0]}
  set -e
  if [ "$status" -ne 0 ]; then
    echo "fuzz target $target failed (exit $status); the input is under fuzz/artifacts/$target/" >&2
    exit 1
  fi
done
