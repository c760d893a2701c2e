#!/usr/bin/env bash
# The probe and variant binaries as one solid archive, so that they fit the device tool's 64 MiB
# carry beside .gpu/payload.tar.xz and .gpu/scenes.tar.xz: each binary is ~5.3 MB as its own .xz
# but they share most of their code, and one xz stream with a dictionary larger than a binary
# keeps each only once (twelve binaries: 64 MB as separate files, 7.3 MB together).
#   Here, after `bash scripts/gpu-probe.sh build` and/or `bash scripts/gpu-variants.sh build`:
#     bash scripts/gpu-extras.sh pack     (.gpu/probe-*.xz, .gpu/variant-*.xz -> .gpu/extras.tar.xz;
#                                          about 2 min on two cores)
#   On the GPU, `scripts/gpu-all.sh` runs `bash scripts/gpu-extras.sh unpack` first (back to
#   .gpu/NAME.xz, quickly compressed, for gpu-probe.sh and gpu-variants.sh).
set -eu
case "${1:-}" in
pack)
  files=$(ls .gpu/probe-*.xz .gpu/variant-*.xz 2> /dev/null || true)
  [ -n "$files" ] || { echo "no .gpu/probe-*.xz or .gpu/variant-*.xz to pack"; exit 1; }
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  for f in $files; do xz -dc "$f" > "$tmp/$(basename "$f" .xz)"; done
  tar -C "$tmp" -cf - . | xz -T1 --lzma2=preset=9e,dict=192MiB > .gpu/extras.tar.xz
  rm -f $files
  echo "packed $(echo $files | wc -w) binaries: .gpu/extras.tar.xz ($(du -h .gpu/extras.tar.xz | cut -f1))"
  ;;
unpack)
  [ -f .gpu/extras.tar.xz ] || exit 0
  tmp=$(mktemp -d)
  xz -dc .gpu/extras.tar.xz | tar -x -C "$tmp"
  for f in "$tmp"/*; do xz -0 -T0 -c "$f" > ".gpu/$(basename "$f").xz"; done
  rm -rf "$tmp"
  ;;
*)
  echo "usage: bash scripts/gpu-extras.sh pack|unpack"
  exit 1
  ;;
esac
