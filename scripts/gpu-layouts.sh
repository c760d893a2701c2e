#!/usr/bin/env bash
# The binary-vs-wide trace table and the per-stage build times on a lent GPU, in one `device` call.
# Here, first:   bash ../shared/gpu/pack.sh
# Then `run` with carry [".gpu", ".gl"] and the command:   bash scripts/gpu-layouts.sh
# (`bash .gpu/run.sh tests bench` is the other call: the test binaries and the standard table.)
# Every scene below is built by lbvh, trbvh and trbvh-split and each tree traced in both layouts,
# 1920x1080, 4 spp, after 0.5 s of warm-up, median of 21. JSON lines go to $OUT/layouts.jsonl, a
# table is printed last, after one of the SAH-optimal wide collapse (`--wide-collapse optimal`, its
# program on the GPU) against the greedy one (the default) for trbvh on OPTIMAL_SCENES: trace
# speed, nodes and the time of the build stage "wide".
# SCENES overrides the scene list, W H SPP REPEATS the workload, NAME the JSON file's name
# (default layouts: $OUT/NAME.jsonl); with
# TREELET set to a treelet binary it runs that one here instead (a dry run, e.g. on lavapipe:
# TREELET=target/release/treelet SCENES=cornell W=64 H=64 SPP=1 REPEATS=1 bash scripts/gpu-layouts.sh).
set -u
. scripts/gpu-env.sh
json="$out/${NAME:-layouts}.jsonl"
log="$out/${NAME:-layouts}.log"
: > "$json"
for s in ${SCENES:-conference crytek_sponza sibenik lost_empire armadillo dabrovic_sponza field:707}; do
  timeout 150 "$bin" bench --scene "$s" --builder lbvh,trbvh,trbvh-split --layout binary,wide --tune-schedule off \
    --width "${W:-1920}" --height "${H:-1080}" --spp "${SPP:-4}" --repeats "${REPEATS:-21}" >> "$json" 2>> "$log" \
    || echo "$s: exit $? (see $log)"
done
# The SAH-optimal collapse against the greedy one, both converted on the GPU, trbvh.
for s in ${OPTIMAL_SCENES:-conference crytek_sponza lost_empire}; do
  timeout 100 "$bin" bench --scene "$s" --builder trbvh --layout wide --wide-collapse optimal --tune-schedule off \
    --width "${W:-1920}" --height "${H:-1080}" --spp "${SPP:-4}" --repeats "${REPEATS:-21}" >> "$json" 2>> "$log" \
    || echo "$s optimal collapse: exit $? (see $log)"
done
python3 - "$json" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
optimal = [r for r in rows if r.get("wide_collapse") == "optimal"]
rows = [r for r in rows if r.get("wide_collapse") != "optimal"]
print("scene            trbvh wide: greedy Mrays/s  optimal Mrays/s  optimal/greedy  nodes greedy/optimal  wide ms greedy/optimal")
for o in optimal:
    g = next((r for r in rows if r["scene"] == o["scene"] and r["builder"] == "trbvh"
              and r["layout"] == "wide"), None)
    if g:
        print(f"{o['scene'][-16:]:16} {g['mrays_per_s'] or 0:27.1f} {o['mrays_per_s'] or 0:16.1f}"
              f" {(o['mrays_per_s'] or 0) / (g['mrays_per_s'] or 1):15.2f}"
              f" {g['nodes']:>12}/{o['nodes']}"
              f" {g['stages_ms'].get('wide') or 0:10.2f}/{o['stages_ms'].get('wide') or 0:.2f}")
def steps(r, key):
    # The traversal steps per ray of the same rays (bench's counting trace).
    return f"{r['steps'][key]:.1f}" if r.get("steps") else "-"
runs = {}
for r in rows:
    runs.setdefault((r["scene"], r["builder"]), {})[r["layout"]] = r
print("scene            builder      build ms  wide ms  disp  wide levels/disp  binary Mrays/s  wide Mrays/s  wide/binary  bytes w/b  nodes/ray b/w  tris/ray b/w")
for (scene, builder), l in runs.items():
    b, w = l.get("binary"), l.get("wide")
    if not (b and w):
        continue
    ratio = (w["mrays_per_s"] or 0) / (b["mrays_per_s"] or 1)
    print(f"{scene[-16:]:16} {builder:11} {b['build_ms']:9.2f} {w['stages_ms'].get('wide') or 0:8.2f}"
          f" {b['dispatches']:5} {w.get('wide_levels') or 0:8}/{w['stages_dispatches'].get('wide') or 0:<8}"
          f" {b['mrays_per_s'] or 0:15.1f} {w['mrays_per_s'] or 0:13.1f}"
          f" {ratio:12.2f} {w['tree_bytes'] / b['tree_bytes']:10.2f}"
          f" {steps(b, 'nodes_per_ray')}/{steps(w, 'nodes_per_ray')}"
          f" {steps(b, 'triangles_per_ray')}/{steps(w, 'triangles_per_ray')}")
    # Both layouts trace the same paths: their ray counts agree but for ties (an H200 once counted
    # 5 % of crytek_sponza's rays through the wide layout, and its Mrays/s meant nothing).
    if abs(w["rays"] - b["rays"]) > 0.002 * b["rays"]:
        print(f"  WRONG: {scene} {builder}: the wide layout traced {w['rays']} rays, the binary {b['rays']}")
print("per-stage build ms (binary runs):")
for (scene, builder), l in runs.items():
    if "binary" in l:
        stages = " ".join(f"{k} {v:.2f}" for k, v in l["binary"]["stages_ms"].items() if v is not None)
        print(f"  {scene[-16:]:16} {builder:11} {stages}")
PY
