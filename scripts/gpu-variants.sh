#!/usr/bin/env bash
# Changes measured on lavapipe whose effect on a GPU is the open question, timed on a lent GPU
# beside this commit's binary. Each variant is a patch in scripts/variants/ (against this
# commit); its first lines say what it changes and what lavapipe measured ("# ..."), how to time
# it ("# bench: OPTIONS") and on which scenes ("# scenes: S ..."). git apply skips those lines.
#   Here, after `bash ../shared/gpu/pack.sh`:   bash scripts/gpu-variants.sh build
#     (an incremental release build per variant, packed as .gpu/variant-NAME.xz; the working tree
#     is restored after each, also on failure; a patch that no longer applies is reported and
#     skipped)
#   On the GPU (`run` with carry [".gpu", ".gl"]):   bash scripts/gpu-variants.sh run
#     (or as the "variants" step of scripts/gpu-all.sh, which runs it when variants are packed):
#     per variant and scene, this commit's binary and the variant's in turn (TURNS times, default
#     1: each bench already takes the median of its repeats after warm-up); JSON lines in
#     $OUT/variants.jsonl and a table of build ms and Mrays/s (medians), main against variant.
#     Variants run in the order ORDER gives (default: those whose answer decides the most first),
#     then the other packed ones.
#   A dry run of `run` on lavapipe, after `build` (SCENES and BENCH_OPTS replace every variant's):
#     TREELET=target/release/treelet SCENES=cornell_box BENCH_OPTS="--builder trbvh --width 16
#     --height 16 --spp 1 --repeats 1 --warmup-ms 0" bash scripts/gpu-variants.sh run
set -eu
case "${1:-}" in
build)
  [ -f "$HOME/.cargo/env" ] && . "$HOME/.cargo/env"
  # Restoring checks out shaders/ and src/: refuse to start with changes there to lose.
  git diff --quiet -- shaders src || { echo "uncommitted changes in shaders/ or src/: commit or stash them first"; exit 1; }
  mkdir -p .gpu
  rm -f .gpu/variant-*.xz
  restore() { git checkout -- shaders src; }
  trap restore EXIT
  shopt -s nullglob
  patches=(scripts/variants/*.patch)
  [ ${#patches[@]} -gt 0 ] || echo "no scripts/variants/*.patch: no variant to build"
  for patch in "${patches[@]}"; do
    name=$(basename "$patch" .patch)
    if ! git apply --check "$patch" 2>/dev/null; then
      echo "variant $name: the patch no longer applies to this commit; skipped"
      continue
    fi
    git apply "$patch"
    cargo build --release --quiet
    strip -o /tmp/treelet-variant target/release/treelet
    xz -T2 -6 -c /tmp/treelet-variant > ".gpu/variant-$name.xz"
    restore
    echo "variant $name: .gpu/variant-$name.xz"
  done
  cargo build --release --quiet
  ;;
run)
  . scripts/gpu-env.sh
  dir=/tmp/treelet-variants
  mkdir -p "$dir"
  : > "$out/variants.jsonl"
  ls .gpu/variant-*.xz > /dev/null 2>&1 || { echo "no .gpu/variant-*.xz: run 'bash scripts/gpu-variants.sh build' first"; exit 1; }
  # The variants whose answer decides the most first (a capped run keeps those), then any others.
  first="${ORDER:-}"
  names=$( (for n in $first; do [ -f ".gpu/variant-$n.xz" ] && echo "$n"; done
    for f in .gpu/variant-*.xz; do n=$(basename "$f" .xz); echo "${n#variant-}"; done) | awk '!seen[$0]++')
  for name in $names; do
    f=.gpu/variant-$name.xz
    patch=scripts/variants/$name.patch
    xz -dc "$f" > "$dir/$name" && chmod +x "$dir/$name"
    # A throwaway bench first: on an H200 the first scene of three of five variants timed the
    # variant's build 3-4 times slower than its later scenes did (README, "On an NVIDIA H200,
    # third session"); a first run's cost, it seems, not the variant's.
    timeout 30 "$dir/$name" bench --scene cornell --builder trbvh --width 16 --height 16 --spp 1 \
      --repeats 3 --tune-schedule off > /dev/null 2>&1 || true
    opts=${BENCH_OPTS:-$(sed -n 's/^# bench: //p' "$patch")}
    scenes=${SCENES:-$(sed -n 's/^# scenes: //p' "$patch")}
    for s in $scenes; do
      for turn in $(seq "${TURNS:-1}"); do
        for exe in "$bin" "$dir/$name"; do
          tag=main
          [ "$exe" = "$bin" ] || tag=$name
          # shellcheck disable=SC2086
          timeout 60 "$exe" bench --scene "$s" $opts --tune-schedule off 2>> "$out/variants.log" \
            | sed "s/^{/{\"variant\":\"$name\",\"binary\":\"$tag\",\"turn\":$turn,/" >> "$out/variants.jsonl" \
            || echo "$name $s $tag: exit $? (see variants.log)"
        done
      done
    done
  done
  python3 - "$out/variants.jsonl" <<'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
print("variant          scene            builder      layout  binary           build ms  treelets ms  wide ms  Mrays/s        rays   sah")
keys = dict.fromkeys((r["variant"], r["scene"], r["builder"], r["layout"]) for r in rows)
for v, s, b, l in keys:
    for tag in ("main", v):
        g = [r for r in rows if (r["variant"], r["scene"], r["builder"], r["layout"], r["binary"]) == (v, s, b, l, tag)]
        if not g:
            continue
        build = statistics.median(r["build_ms"] for r in g)
        mrays = statistics.median(r.get("mrays_per_s") or 0 for r in g)
        stage = lambda r, *names: sum(r["stages_ms"].get(n) or 0 for n in names)
        treelets = statistics.median(stage(r, "treelets", "treelets climb") for r in g)
        wide = statistics.median(stage(r, "wide") for r in g)
        print(f"{v[:16]:16} {s[-16:]:16} {b:12} {l:7} {tag[:16]:16} {build:8.3f} {treelets:12.3f} {wide:8.3f}"
              f" {mrays:8.1f} {g[0].get('rays') or 0:11}  {g[0]['sah']:.4f}")
PY
  ;;
*)
  echo "usage: bash scripts/gpu-variants.sh build|run"
  exit 1
  ;;
esac
