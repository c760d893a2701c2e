#!/usr/bin/env bash
# Runs treelet's main job: installs what it needs, builds, and renders the default scene.
# Extra arguments go to `treelet` (e.g. `scripts/run.sh bench --scene conference`).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
if [ -f "$HOME/.cargo/env" ]; then . "$HOME/.cargo/env"; fi
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp/treelet-xdg-$(id -u)}"
mkdir -p "$XDG_RUNTIME_DIR" && chmod 700 "$XDG_RUNTIME_DIR"
cargo build --release
exec ./target/release/treelet "$@"
