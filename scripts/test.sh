#!/usr/bin/env bash
# Runs treelet's test suite: installs what it needs (Vulkan loader + Mesa's software driver when no
# GPU is present, Xvfb, Rust), then checks formatting and lints, runs every test on the GPU adapter
# found (the software driver in CI), builds the core library without the viewer and runs its
# example, compiles every kernel with a GPU compiler and checks that none spills (Mesa's RADV
# without a GPU, where installed; always in CI), and opens the viewer once
# (scripts/viewer-smoke.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
if [ -f "$HOME/.cargo/env" ]; then . "$HOME/.cargo/env"; fi
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp/treelet-xdg-$(id -u)}"
mkdir -p "$XDG_RUNTIME_DIR" && chmod 700 "$XDG_RUNTIME_DIR"
rustup component add rustfmt clippy >/dev/null 2>&1 || true
cargo fmt --check
cargo clippy --release --all-targets -- -D warnings
cargo test --release
# The core library alone (no viewer, command line or charts) compiles; its example runs (built with
# the default features so that it reuses the test build: a no-default-features build recompiles
# wgpu with other dependency features, minutes on two cores).
cargo check --release --no-default-features --lib --examples
cargo run --release --example build_bvh
# Every kernel compiles with a GPU driver's compiler too (RADV with a null device; README, "Kernel
# statistics"), and there none spills a vector register (treelets of 7 leaves; the wide
# conversion's kernels with each collapse, the trace kernels without point lights, the
# collapse's mark without references, the any-hit ray queries, the phases' roots taking their
# slots one by one and the treelet kernels without the team path and the next round's levels:
# pipeline constants).
if [ -f /usr/share/vulkan/icd.d/radeon_icd.json ]; then
  bash scripts/shader-stats.sh > target/shader-stats.txt
  bash scripts/shader-stats.sh wide_nodes WIDE_COLLAPSE=1 >> target/shader-stats.txt
  bash scripts/shader-stats.sh paths_trace POINT_LIGHTS=0 >> target/shader-stats.txt
  bash scripts/shader-stats.sh nodes_mark HAS_REFS=0 >> target/shader-stats.txt
  bash scripts/shader-stats.sh rays_intersect ANY_HIT=1 >> target/shader-stats.txt
  bash scripts/shader-stats.sh roots_phase AGGREGATE_ROOTS=0 >> target/shader-stats.txt
  bash scripts/shader-stats.sh treelets waves subtrees TREELET_TEAMS=0 NEXT_LEVELS=0 >> target/shader-stats.txt
  if grep -E "Spilled VGPRs=[1-9]" target/shader-stats.txt; then
    echo "error: the kernels above spill registers on RADV (target/shader-stats.txt)"
    exit 1
  fi
elif [ -n "${CI:-}" ]; then
  echo "error: no RADV (mesa-vulkan-drivers) to compile the kernels with"; exit 1
else
  echo "skipped: the kernels' GPU compile (no RADV: mesa-vulkan-drivers)"
fi
bash scripts/viewer-smoke.sh
