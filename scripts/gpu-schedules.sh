#!/usr/bin/env bash
# The treelet rounds' schedule on a lent GPU, in one `device` call, per scene, trbvh (7,3): the
# default, each pair of --treelet-dp and --climb-dp, the rounds overlapped (--round-overlap at
# each of OVERLAPS, default 6: fewer waves dispatched (OVERLAP_LEVELS per round, the rest climbed),
# and the loop DP at the default count), teams in the dispatched levels (--team-below, the
# climb's left without; also with TEAM_LEVELS levels dispatched, default 20 and 32: small levels
# by teams instead of the climb), teams in the climb's small waves (--climb-team-below), and with
# LEVELS set every combination of those --level-dispatches and --team-below (the defaults came
# from such a sweep in the first H200 session; the same tree each time, tested); then lbvh and
# trbvh at each --climb-width.
# Here, first:   bash ../shared/gpu/pack.sh
# Then `run` with carry [".gpu", ".gl"] and the command:   bash scripts/gpu-schedules.sh
# JSON lines go to $OUT/schedules.jsonl and $OUT/climbs.jsonl; a table of the climb widths, then
# one of build ms and the two treelet stages, fastest first per scene, are printed last. SCENES,
# LEVELS, TEAMS, TEAM_LEVELS, CLIMB_TEAMS, DPS, OVERLAPS, OVERLAP_LEVELS, CLIMBS and REPEATS
# override the sweep; with TREELET set to a treelet binary it runs that one here instead (a dry
# run on lavapipe: TREELET=target/release/treelet SCENES=field:100 LEVELS=0,4 TEAMS=0,64
# TEAM_LEVELS=20 CLIMB_TEAMS=5 OVERLAP_LEVELS=8 CLIMBS=32 REPEATS=1 bash scripts/gpu-schedules.sh).
set -u
. scripts/gpu-env.sh
: > "$out/schedules.jsonl"
for s in ${SCENES:-conference sibenik field:707}; do
  # The default schedule first, then the one a tuning keeps (`--tune-schedule on`: its trials in
  # the JSON), the DP's forms, the overlapped rounds, teams, then the sweep (a schedule option
  # turns the tuning off).
  sweep=""
  if [ -n "${LEVELS:-}" ]; then
    sweep="--level-dispatches $LEVELS --team-below ${TEAMS:-0,256,1024,4096}"
  fi
  for opts in "--tune-schedule off" "--tune-schedule on" "--treelet-dp ${DPS:-unrolled,loop} --climb-dp ${DPS:-unrolled,loop}" \
      "--round-overlap ${OVERLAPS:-6}" \
      "--round-overlap ${OVERLAPS:-6} --level-dispatches ${OVERLAP_LEVELS:-8,11}" \
      "--round-overlap ${OVERLAPS:-6} --treelet-dp loop" \
      "--team-below ${TEAMS:-256,1024,4096}" "--climb-team-below ${CLIMB_TEAMS:-5,9}" \
      "--level-dispatches ${TEAM_LEVELS:-20,32} --team-below 0,${TEAMS:-256,1024,4096}" \
      ${sweep:+"$sweep"}; do
    # shellcheck disable=SC2086
    timeout 200 "$bin" bench --scene "$s" --builder trbvh $opts --width 64 --height 64 --spp 1 \
      --repeats "${REPEATS:-11}" >> "$out/schedules.jsonl" 2>> "$out/schedules.log" \
      || echo "$s $opts: exit $? (see schedules.log)"
  done
done
# The climbs' workgroup width (`--climb-width`; one value per run: it is a device option), lbvh
# and trbvh, the default (64) first.
: > "$out/climbs.jsonl"
for s in ${SCENES:-conference sibenik field:707}; do
  for width in 64 ${CLIMBS:-32 128 256}; do
    timeout 100 "$bin" bench --scene "$s" --builder lbvh,trbvh --climb-width "$width" --tune-schedule off --width 64 \
      --height 64 --spp 1 --repeats "${REPEATS:-11}" >> "$out/climbs.jsonl" \
      2>> "$out/schedules.log" || echo "$s climb width $width: exit $? (see schedules.log)"
  done
done
python3 - "$out/climbs.jsonl" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
print("scene            builder  climb width  build ms  hierarchy ms  treelets ms  sah")
for r in rows:
    st = r["stages_ms"]
    print(f"{r['scene'][-16:]:16} {r['builder']:8} {r['climb_width']:11} {r['build_ms']:9.3f}"
          f" {st.get('hierarchy') or 0:13.3f} {st.get('treelets') or 0:12.3f} {r['sah']:.4f}")
PY
python3 - "$out/schedules.jsonl" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
print("scene            levels  team_below  climb teams  dp        climb dp  overlap  build ms  treelets ms  climb ms  dispatches  sah")
for scene in dict.fromkeys(r["scene"] for r in rows):
    runs = sorted((r for r in rows if r["scene"] == scene), key=lambda r: r["build_ms"])
    for r in runs:
        st = r["stages_ms"]
        levels = "auto" if r["level_dispatches"] is None else r["level_dispatches"]
        overlap = "none" if r.get("round_overlap") is None else r["round_overlap"]
        print(f"{scene[-16:]:16} {levels:>6} {r['team_below']:>11} {r.get('climb_team_below', 0):>12}"
              f" {r['treelet_dp']:9} {r['climb_dp']:9}"
              f" {overlap:>7}"
              f" {r['build_ms']:9.3f}"
              f" {st.get('treelets') or 0:12.3f} {st.get('treelets climb') or 0:9.3f}"
              f" {r['dispatches']:11} {r['sah']:.4f}"
              + ("  (tuned)" if r.get("schedule_tuning") else ""))
PY
