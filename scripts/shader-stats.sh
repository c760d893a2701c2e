#!/usr/bin/env bash
# Registers, spills and code size of the kernels from a real GPU compiler on a machine without a
# GPU: Mesa's RADV with a null device (RADV_FORCE_FAMILY, default navi31 = RDNA 3) compiles each
# kernel as examples/shader_stats.rs hands it over (README, "Kernel statistics"). Arguments go to
# the example (kernel name filters, NAME=value constants).
#   bash scripts/shader-stats.sh [FILTER...] [NAME=value...]
#   bash scripts/shader-stats.sh pack     (the example, stripped, as .gpu/shader-stats.xz: after
#                                          ../shared/gpu/pack.sh, for gpu-all.sh's step
#                                          "kernelstats", which reports the lent GPU's compiler)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --example shader_stats >&2
if [ "${1:-}" = pack ]; then
  mkdir -p .gpu
  strip -o /tmp/shader-stats target/release/examples/shader_stats
  xz -T2 -6 -c /tmp/shader-stats > .gpu/shader-stats.xz
  echo "packed .gpu/shader-stats.xz ($(du -h .gpu/shader-stats.xz | cut -f1))"
  exit 0
fi
icd=/usr/share/vulkan/icd.d/radeon_icd.json
[ -f "$icd" ] || { echo "error: no RADV ($icd): install mesa-vulkan-drivers" >&2; exit 1; }
RADV_FORCE_FAMILY="${RADV_FORCE_FAMILY:-navi31}" VK_ICD_FILENAMES="$icd" \
    target/release/examples/shader_stats "$@" 2> >(grep -v "invalid pci bus info" >&2)
