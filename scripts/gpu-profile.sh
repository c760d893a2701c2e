#!/usr/bin/env bash
# Every dispatch of a build timed on its own on a lent GPU, in one `device` call: `bench
# --profile-dispatches` per scene for lbvh, trbvh and trbvh-split (each dispatch in a compute pass
# of its own, so the sums run a little above a normal build's stages), with the radix sort's
# default tiles and with each tile size (`--sort-tile-items`).
# Here, first:   bash ../shared/gpu/pack.sh
# Then `run` with carry [".gpu", ".gl"] and the command:   bash scripts/gpu-profile.sh
# JSON lines go to $OUT/$NAME.jsonl (NAME: profile by default); printed last, per scene and
# builder with the default tiles:
# each stage's dispatches by kernel (count, total, min/median/max ms), then the treelet rounds
# dispatch by dispatch, and the wide conversion's levels when EXTRA="--layout wide" converts the
# trees; then build and sort ms per tile size. SCENES, BUILDERS, TILES, REPEATS and EXTRA (more
# bench options) override the defaults; with TREELET set to a treelet binary it runs
# that one here instead (a dry run on lavapipe:
# TREELET=target/release/treelet SCENES=field:100 REPEATS=1 bash scripts/gpu-profile.sh).
set -u
. scripts/gpu-env.sh
: > "$out/${NAME:-profile}.jsonl"
for s in ${SCENES:-conference sibenik field:707 field:1000}; do
  for tile in ${TILES:-default 8 16 32}; do
    opts=""
    [ "$tile" = default ] || opts="--sort-tile-items $tile"
    # shellcheck disable=SC2086
    timeout 250 "$bin" bench --scene "$s" --builder "${BUILDERS:-lbvh,trbvh,trbvh-split}" $opts --tune-schedule off ${EXTRA:-} \
      --profile-dispatches --width 64 --height 64 --spp 1 --repeats "${REPEATS:-11}" \
      >> "$out/${NAME:-profile}.jsonl" 2>> "$out/${NAME:-profile}.log" \
      || echo "$s $tile: exit $? (see ${NAME:-profile}.log)"
  done
done
python3 - "$out/${NAME:-profile}.jsonl" <<'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
for r in (r for r in rows if r["sort_tile_items"] is None):
    d = r["dispatch_ms"]
    print(f"\n{r['scene']} {r['builder']}: build {r['build_ms']:.3f} ms (median), "
          f"{len(d)} dispatches summing to {sum(x['ms'] or 0 for x in d):.3f} ms")
    groups = {}
    for x in d:
        groups.setdefault((x["stage"], x["kernel"]), []).append(x["ms"] or 0)
    for (stage, kernel), ms in groups.items():
        print(f"  {stage:16} {kernel:20} {len(ms):3} x  total {sum(ms):8.3f}  "
              f"min {min(ms):7.3f}  median {statistics.median(ms):7.3f}  max {max(ms):7.3f}")
    rounds = [x for x in d if x["stage"].startswith("treelets")]
    if rounds:
        print("  treelet rounds, in order (ms): " + " ".join(
            ("|" if x["kernel"] == "nodes_level" else "") + f"{x['ms'] or 0:.3f}" for x in rounds))
    wide = [x for x in d if x["stage"] == "wide"]
    if wide:
        print("  wide conversion, in order (ms): " + " ".join(f"{x['ms'] or 0:.3f}" for x in wide))
print("\nscene            builder      tile     build ms   sort ms  sah")
for r in rows:
    tile = "default" if r["sort_tile_items"] is None else r["sort_tile_items"]
    print(f"{r['scene'][-16:]:16} {r['builder']:12} {tile:>7} {r['build_ms']:10.3f}"
          f" {r['stages_ms'].get('sort') or 0:9.3f}  {r['sah']:.4f}")
PY
