#!/usr/bin/env bash
# Runs treelet's test suite: installs what it needs (Vulkan loader + Mesa's software driver when no
# GPU is present, Xvfb, Rust), then checks formatting and lints and runs every test on the GPU
# adapter found (the software driver in CI).
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
bash scripts/viewer-smoke.sh
