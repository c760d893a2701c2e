#!/usr/bin/env bash
# Runs treelet's test suite: installs what it needs (Vulkan loader + Mesa's software driver when no
# GPU is present, Xvfb, Rust), then checks formatting and lints, runs every test on the GPU adapter
# found (the software driver in CI), builds the core library without the viewer and runs its
# example, and opens the viewer once (scripts/viewer-smoke.sh).
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
bash scripts/viewer-smoke.sh
