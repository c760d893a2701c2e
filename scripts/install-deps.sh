#!/usr/bin/env bash
# Installs what treelet needs on a fresh Debian/Ubuntu machine:
#   - a Vulkan driver: when no GPU Vulkan adapter is present, Mesa's software driver (lavapipe).
#     On Debian 12 (bookworm) it comes from bookworm-backports (Mesa 25): Debian 12's own Mesa 22.3
#     lavapipe silently ends shader loops after 65,535 iterations and draws egui text as boxes.
#   - the Vulkan loader, Xvfb (for the viewer smoke test) and a Rust toolchain if cargo is missing.
# Safe to run repeatedly; does nothing that is already done.
set -euo pipefail

SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi

have_gpu_vulkan() {
  command -v vulkaninfo >/dev/null 2>&1 || return 1
  vulkaninfo --summary 2>/dev/null | grep -E "deviceType *= *PHYSICAL_DEVICE_TYPE_(DISCRETE|INTEGRATED)_GPU" >/dev/null
}

lavapipe_ok() {
  # Mesa >= 25 lavapipe ICD present.
  local v
  v=$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)
  [ -n "$v" ] && dpkg --compare-versions "$v" ge 25
}

need_pkgs=()
dpkg -s libvulkan1 >/dev/null 2>&1 || need_pkgs+=(libvulkan1)
dpkg -s xvfb >/dev/null 2>&1 || need_pkgs+=(xvfb)
dpkg -s libxkbcommon-x11-0 >/dev/null 2>&1 || need_pkgs+=(libxkbcommon-x11-0)
dpkg -s vulkan-tools >/dev/null 2>&1 || need_pkgs+=(vulkan-tools)

if [ ${#need_pkgs[@]} -gt 0 ] || { ! have_gpu_vulkan && ! lavapipe_ok; }; then
  export DEBIAN_FRONTEND=noninteractive
  codename=$(. /etc/os-release; echo "${VERSION_CODENAME:-}")
  backports=""
  if [ "$codename" = bookworm ]; then
    # Add bookworm-backports with the same URIs as the machine's existing Debian sources.
    if ! grep -rqs "bookworm-backports" /etc/apt/sources.list /etc/apt/sources.list.d/; then
      uri=""
      if [ -f /etc/apt/sources.list.d/debian.sources ]; then
        uri=$(awk '/^URIs:/{print $2; exit}' /etc/apt/sources.list.d/debian.sources)
      fi
      if [ -z "$uri" ] && [ -f /etc/apt/sources.list ]; then
        uri=$(awk '$1=="deb" && $3 ~ /^bookworm$/ {print $2; exit}' /etc/apt/sources.list)
      fi
      if [ -n "$uri" ]; then
        printf 'Types: deb\nURIs: %s\nSuites: bookworm-backports\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' "$uri" \
          | $SUDO tee /etc/apt/sources.list.d/bookworm-backports.sources >/dev/null
      fi
    fi
    backports="-t bookworm-backports"
  fi
  $SUDO apt-get update -q
  if [ ${#need_pkgs[@]} -gt 0 ]; then $SUDO apt-get install -y -q "${need_pkgs[@]}"; fi
  if ! have_gpu_vulkan; then
    # shellcheck disable=SC2086
    $SUDO apt-get install -y -q $backports mesa-vulkan-drivers libvulkan1
  fi
fi

if ! command -v cargo >/dev/null 2>&1; then
  if [ -f "$HOME/.cargo/env" ]; then . "$HOME/.cargo/env"; fi
fi
if ! command -v cargo >/dev/null 2>&1; then
  curl -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal
  . "$HOME/.cargo/env"
fi
