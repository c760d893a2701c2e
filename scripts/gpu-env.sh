# Sourced by the scripts that run on a lent GPU (gpu-layouts.sh, gpu-schedules.sh,
# gpu-profile.sh): sets `out` (the folder whose files come back, $OUT) and `bin` (the treelet
# binary). With TREELET set to a treelet binary it uses that one here (dry runs, e.g. on
# lavapipe); otherwise .gpu/run.sh unpacks the binary and the scenes into /tmp/treelet-gpu and
# checks that the GPU opens.
out=${OUT:-/tmp/out}
mkdir -p "$out"
bin=${TREELET:-}
if [ -z "$bin" ]; then
  bash .gpu/run.sh -- scenes > "$out/scenes.txt" 2>&1 || { cat "$out/scenes.txt"; exit 1; }
  work=/tmp/treelet-gpu
  bin=$work/treelet
  [ -x "$bin" ] || { echo "no $bin: .gpu/run.sh unpacks elsewhere now"; exit 1; }
  export TREELET_SCENES_DIR=$work/scenes
  icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
  [ -f $icd ] && export VK_DRIVER_FILES=$icd
fi
