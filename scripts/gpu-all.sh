#!/usr/bin/env bash
# Everything a lent GPU is asked to measure, in one `device` call that fits a short lease, step by
# step in this order (the trace's correctness and the build's figures first): the test binaries
# ("tests"), each kernel's registers and spills from the GPU's compiler ("kernelstats", when
# `bash scripts/shader-stats.sh pack` packed the example), the phased rounds beside the
# bottom-up ones ("phases"; PHASE_SCENES), teams of 32
# invocations per treelet in the dispatched levels, in the overlapped rounds' dispatched waves and
# in the climb, each threshold beside none ("teams"; TEAM_SCENES), the treelet rounds' lowest
# levels per subtree at each height beside by level ("subtrees"), every build with wgpu's indirect validation on and off ("indirect"), the
# binary-vs-wide table ("layouts"), the same on the stress scenes ("stress"), build scaling with each GPU builder's schedule
# tuned ("scaling"), the round schedules each fixed beside the default and the tuned one (the
# DP's forms in the dispatched levels and the climb, the overlapped rounds, the team thresholds
# TEAMS and CLIMB_TEAMS, and levels dispatched where LEVELS is set: "schedules"), the changes of scripts/variants/
# beside this commit ("variants", when `bash scripts/gpu-variants.sh build` packed them), the wide
# conversion's level dispatches ("widelevels"), where a treelet level's time goes ("probe", when
# `bash scripts/gpu-probe.sh build` packed its variants), every dispatch of lbvh timed per sort
# tile ("profile") and every dispatch of trbvh and trbvh-split with the wide conversion timed
# ("kernels"). Each step is capped
# so that the whole run ends within BUDGET seconds (default 500; STEPS picks some of the steps, e.g.
# STEPS="tests schedules"). After every step the results so far are packed into $OUT/results.tar.gz,
# so a call stopped at its limit still brings back what ran. A summary is printed last.
# Here, first:   bash ../shared/gpu/pack.sh,   bash scripts/shader-stats.sh pack,
#   bash scripts/gpu-probe.sh build,
#   bash scripts/gpu-variants.sh build   and   bash scripts/gpu-extras.sh pack   (without the last,
#   the binaries overrun the device tool's 64 MiB carry)
# (optionally also a baseline binary: xz -c OLD/treelet > .gpu/base-treelet.xz, timed beside the
# new one on the same GPU), then `run` with carry [".gpu", ".gl"], timeout_s 600 and the command:
#   bash scripts/gpu-all.sh
set -u
start=$(date +%s)
budget=${BUDGET:-500}
final=${OUT:-/tmp/out}
mkdir -p "$final"
res=/tmp/gpu-all
rm -rf $res
mkdir -p $res/tests
elapsed() { echo $(($(date +%s) - start)); }
save() { tar -C $res -czf "$final/results.tar.gz" .; }
# step NAME CAP COMMAND...: runs COMMAND with at most CAP seconds (less if the budget is short),
# its output in NAME.txt.
step() {
  local name=$1 cap=$2 left
  shift 2
  case " ${STEPS:-tests kernelstats phases teams subtrees indirect layouts stress scaling schedules variants widelevels probe profile kernels} " in
    *" $name "*) ;;
    *) return ;;
  esac
  left=$((budget - $(elapsed)))
  if [ $left -lt 15 ]; then
    echo "== $name: skipped (budget spent)"
    return
  fi
  [ "$cap" -gt $left ] && cap=$left
  echo "== $name (at $(elapsed) s, cap $cap s)"
  timeout "$cap" "$@" > "$res/$name.txt" 2>&1
  echo "   rc=$? after $(elapsed) s"
  save
}

# The probe and variant binaries, when they came as one archive (scripts/gpu-extras.sh pack).
bash scripts/gpu-extras.sh unpack
# Unpack the binaries and scenes once (.gpu/run.sh with no mode), then run from there.
OUT=$res bash .gpu/run.sh > $res/setup.txt 2>&1 || { cat $res/setup.txt; save; exit 1; }
cat $res/setup.txt
work=/tmp/treelet-gpu
export TREELET=$work/treelet TREELET_SCENES_DIR=$work/scenes OUT=$res
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f $icd ] && export VK_DRIVER_FILES=$icd
manifest=$(cat $work/manifest_dir)
export manifest res
base=""
if [ -f .gpu/base-treelet.xz ]; then
  xz -dc .gpu/base-treelet.xz > $work/base-treelet && chmod +x $work/base-treelet && base=$work/base-treelet
fi

small="--width 64 --height 64 --spp 1 --repeats 21"
scaling() {
  # The treelet builders tune their schedule first (on a GPU by default): the table shows the
  # schedule each kept; the first rows of the step "schedules" time the default one.
  for s in field:224 field:707 field:1000 field:2000 conference crytek_sponza sibenik lost_empire; do
    timeout 60 $TREELET bench --scene $s --builder lbvh,trbvh,trbvh-split $small >> $res/scaling.jsonl
  done
  # Fewer rounds of larger treelets: (8, 2) is within about 1 % of (7, 3)'s SAH on the shared
  # scenes (lavapipe), with a third fewer levels in the chain but a DP three times as long.
  for s in conference field:707; do
    timeout 60 $TREELET bench --scene $s --builder trbvh --treelet-size 7,8 --rounds 2,3 --tune-schedule off $small >> $res/scaling.jsonl
  done
  # A cheaper last round (README, "A cheaper last round"): its treelets of 7, 6 and 5 leaves.
  for s in conference field:707; do
    timeout 40 $TREELET bench --scene $s --builder trbvh --last-round-size 7,6,5 --tune-schedule off $small \
      >> $res/scaling.jsonl
  done
  if [ -n "$base" ]; then
    for s in field:707 conference sibenik; do
      timeout 40 $base bench --scene $s --builder lbvh,trbvh,trbvh-split $small >> $res/baseline.jsonl
    done
  fi
}
export -f scaling
# The wide conversion's level dispatches (the ones past a shallow tree find no work, a deep tree's
# levels past them go to the subtree finish; README, "Level dispatches past the tree").
wide_levels() {
  for s in conference crytek_sponza lost_empire field:707; do
    timeout 40 $TREELET bench --scene $s --builder trbvh --layout wide \
      --wide-level-dispatches 3,6,8,10,12,14,16,20 --tune-schedule off $small >> $res/widelevels.jsonl
  done
}
export -f wide_levels
# The rounds' lowest levels per subtree (`--subtree-levels`: one dispatch for K levels, a
# workgroup per few subtrees) at each height beside by level (0), the default subtree width (128)
# and the levels above dispatched by default; then at 6 with other widths (latency against
# throughput: examples/subtree_schedule.rs counts both), and at 8 with fewer levels above
# dispatched (the rest climbed). The same tree each time.
subtrees() {
  for s in conference sibenik crytek_sponza field:707 field:2000; do
    timeout 40 $TREELET bench --scene $s --builder trbvh --subtree-levels 0,2,4,6,8 --tune-schedule off \
      $small >> $res/subtrees.jsonl
    timeout 30 $TREELET bench --scene $s --builder trbvh --subtree-levels 6 --subtree-width 32,128,1024 \
      --tune-schedule off $small >> $res/subtrees.jsonl
  done
  timeout 30 $TREELET bench --scene conference --builder trbvh --subtree-levels 8 --level-dispatches 8,10,12 \
    --tune-schedule off $small >> $res/subtrees.jsonl
  timeout 40 $TREELET bench --scene conference --builder trbvh-split --subtree-levels 0,4,8 --tune-schedule off \
    $small >> $res/subtrees.jsonl
}
export -f subtrees
# wgpu's validation of indirect dispatch arguments (a dispatch of its own before each indirect
# one; `gpu::instance_flags` turns it off unless WGPU_VALIDATION_INDIRECT_CALL=1): each build
# with it on, then off, in turn (TURNS times, default 2), on the binary layout and the wide one.
indirect() {
  for s in ${INDIRECT_SCENES:-conference sibenik crytek_sponza field:707 field:2000}; do
    for turn in $(seq 1 "${TURNS:-2}"); do
      for v in 1 0; do
        WGPU_VALIDATION_INDIRECT_CALL=$v timeout 40 $TREELET bench --scene $s --builder lbvh,trbvh,trbvh-split \
          --layout binary,wide --tune-schedule off $small | sed "s/^{/{\"indirect_validation\":$v,\"turn\":$turn,/" \
          >> $res/indirect.jsonl
      done
    done
  done
}
export -f indirect
# Teams (a workgroup of 32 invocations per treelet, `--team-below`) in the dispatched levels, then
# in the overlapped rounds' dispatched waves, each threshold beside none; then the climb's teams
# (`--climb-team-below`). The same tree each time (README, "Teams for the small levels").
teams() {
  for s in ${TEAM_SCENES:-conference crytek_sponza sibenik field:707}; do
    timeout 40 $TREELET bench --scene $s --builder trbvh --team-below 0,256,1024,4096 --tune-schedule off \
      $small >> $res/teams.jsonl
    timeout 40 $TREELET bench --scene $s --builder trbvh --round-overlap 6 --team-below 0,256,1024,4096 \
      --tune-schedule off $small >> $res/teams.jsonl
    timeout 30 $TREELET bench --scene $s --builder trbvh --climb-team-below 0,5,9 --tune-schedule off \
      $small >> $res/teams.jsonl
  done
}
export -f teams
# The phased rounds (`--phases`, README "Phased rounds"): each round in 7 phases by depth instead
# of its 20-37 treelet levels bottom-up, the first round in 7 or 14 (SAH -0.3 to +0.35 % from the
# paper's trees on the shared scenes with 14, 28 phases in all), beside the bottom-up rounds, all
# untuned; the whole build, its treelet stages and SAH; then 3 rounds of 6, 4 and 4 phases (the
# preset `phased`, 14 phases; the later rounds' treelets with their leaves within 3 levels of
# their roots, SAH -0.13 to +0.94 % with trbvh-split's) and 4 rounds of 5, 4, 4 and 4 (17, the
# previous preset: -0.60 to +0.75 %). Then on two scenes 4 rounds of 7, and teams of 32 per
# treelet in phases below 2048 treelets and in every phase (the same tree): a phase holds
# thousands of treelets, where the lone DP's throughput matters more than one treelet's latency.
phases() {
  local scenes=${PHASE_SCENES:-conference crytek_sponza sibenik lost_empire field:224 field:707 field:2000}
  # In the order of what decides most, as the step's cap may stop it: the bottom-up rounds
  # (phases 0) against the preset on every scene; teams in the preset's phases; the DP written out
  # against its loop form there (an H200 ran a lone treelet's loop form in about half the time:
  # README, "Where a small treelet level's time goes"); the roots' slots
  # per workgroup (the GPU default) against per root; every dispatch of the preset timed
  # (roots_phase against treelets_optimize, phase by phase); then the previous preset, 7, 7, 7
  # and 14, 7, 7.
  for s in $scenes; do
    timeout 30 $TREELET bench --scene $s --builder trbvh,trbvh-split --preset phased --phases 0,4 \
      --tune-schedule off $small >> $res/phases.jsonl
  done
  for s in conference field:707; do
    timeout 30 $TREELET bench --scene $s --builder trbvh --preset phased \
      --team-below 0,2048,4294967295 --tune-schedule off $small >> $res/phases.jsonl
    timeout 30 $TREELET bench --scene $s --builder trbvh --preset phased \
      --treelet-dp unrolled,loop --tune-schedule off $small >> $res/phases.jsonl
    timeout 30 $TREELET bench --scene $s --builder trbvh --preset phased \
      --root-slots workgroup,root --tune-schedule off $small >> $res/phases.jsonl
    timeout 30 $TREELET bench --scene $s --builder trbvh --preset phased --profile-dispatches \
      --tune-schedule off --width 64 --height 64 --spp 1 --repeats 5 >> $res/phases_profile.jsonl
  done
  for s in $scenes; do
    timeout 30 $TREELET bench --scene $s --builder trbvh,trbvh-split --rounds 4 --phases 4 --first-round-phases 5 \
      --tune-schedule off $small >> $res/phases.jsonl
    timeout 40 $TREELET bench --scene $s --builder trbvh,trbvh-split --phases 7 --first-round-phases 7,14 \
      --tune-schedule off $small >> $res/phases.jsonl
  done
  for s in conference field:707; do
    timeout 20 $TREELET bench --scene $s --builder trbvh --phases 7 --rounds 4 --tune-schedule off $small \
      >> $res/phases.jsonl
    timeout 30 $TREELET bench --scene $s --builder trbvh --phases 7 --first-round-phases 14 \
      --team-below 0,2048,4294967295 --tune-schedule off $small >> $res/phases.jsonl
  done
}
export -f phases
export small base work
tests() {
  # shellcheck disable=SC2016
  ls $work/bin/* | xargs -P 4 -I{} bash -c \
    'n=$(basename {}); cd "$manifest" && timeout 140 {} --test-threads 4 > $res/tests/$n.log 2>&1; echo "$n rc=$?" >> $res/tests/rc.txt'
}
export -f tests
step tests 150 bash -c tests
# The GPU compiler's registers, spills and local memory per kernel (README, "Kernel statistics"),
# for treelets of 7 and 8 leaves, when `bash scripts/shader-stats.sh pack` packed the example.
kernel_stats() {
  xz -dc .gpu/shader-stats.xz > $work/shader-stats && chmod +x $work/shader-stats
  $work/shader-stats
  # The default schedules' treelet pipelines: without the team path, then also without the next
  # round's levels (the phased rounds, a last round); the trace of a scene without point lights
  # (every shared scene); trbvh's collapse (no pre-split references).
  $work/shader-stats treelets waves TREELET_TEAMS=0
  $work/shader-stats treelets_optimize treelets_climb TREELET_TEAMS=0 NEXT_LEVELS=0
  $work/shader-stats paths_trace POINT_LIGHTS=0
  $work/shader-stats nodes_mark HAS_REFS=0
  $work/shader-stats treelets waves subtrees TREELET_SIZE=8
}
export -f kernel_stats
if [ -f .gpu/shader-stats.xz ]; then
  step kernelstats 40 bash -c kernel_stats
fi
step phases 170 bash -c phases
step teams 150 bash -c teams
step subtrees 120 bash -c subtrees
step indirect 150 bash -c indirect
# The trace first: both layouts on every scene (their ray counts must agree), then the variants.
step layouts 80 env SCENES="conference crytek_sponza sibenik lost_empire armadillo" OPTIMAL_SCENES="conference lost_empire" \
  REPEATS=11 bash scripts/gpu-layouts.sh
# The same table on the stress scenes of the trace issue's OptiX table (README, "Scenes").
step stress 60 env NAME=stress SCENES="stacked grass hairball stadium" OPTIMAL_SCENES=" " \
  REPEATS=11 bash scripts/gpu-layouts.sh
# Build scaling with every treelet builder's schedule tuned (bench's default on a GPU; README,
# "Schedule tuning"): the build times to report and the schedule each scene keeps.
step scaling 130 bash -c scaling
# The DP's forms (dispatched levels and climb), the overlapped rounds and teams on real builds,
# each fixed, beside the default and the tuned schedule: the questions the last GPUs left open
# (README, "On an NVIDIA H200, second session", and "Rounds can overlap"). LEVELS adds the sweep
# of levels dispatched.
step schedules 120 env SCENES="${SCHEDULE_SCENES:-conference sibenik field:707 field:2000}" \
  LEVELS="${LEVELS:-}" TEAMS="${TEAMS:-256,1024,4096}" CLIMB_TEAMS="${CLIMB_TEAMS:-5,9}" CLIMBS=" " \
  REPEATS=11 bash scripts/gpu-schedules.sh
if ls .gpu/variant-*.xz > /dev/null 2>&1; then
  step variants 150 env TREELET=$TREELET bash scripts/gpu-variants.sh run
fi
step widelevels 60 bash -c wide_levels
if ls .gpu/probe-*.xz > /dev/null 2>&1; then
  step probe 40 env SCENES="conference" REPEATS=5 TREELET=$TREELET bash scripts/gpu-probe.sh run
fi
step profile 60 env SCENES="conference field:707 field:2000" TILES="default 8 16 32" BUILDERS=lbvh \
  REPEATS=5 bash scripts/gpu-profile.sh
# Every kernel of the treelet builds, pre-splitting, the collapse and the wide conversion included.
step kernels 40 env NAME=kernels SCENES="conference field:707" TILES=default BUILDERS=trbvh,trbvh-split \
  EXTRA="--layout wide" REPEATS=5 bash scripts/gpu-profile.sh

echo "== summary (at $(elapsed) s)"
echo "tests:"
for f in "$res"/tests/*.log; do
  [ -f "$f" ] || continue
  printf '  %-18s %s %s\n' "$(basename "$f" .log)" "$(grep -E "^$(basename "$f" .log) rc=" $res/tests/rc.txt 2>/dev/null | cut -d' ' -f2)" \
    "$(grep -E '^test result' "$f" | tail -1)"
  grep -E '^test .* FAILED$' "$f" | head -8 | sed 's/^/      /'
done
python3 - $res <<'PY'
import json, os, sys
res = sys.argv[1]
def rows(name):
    p = os.path.join(res, name)
    return [json.loads(l) for l in open(p) if l.startswith("{")] if os.path.exists(p) else []
def round_rows(name, title, columns):
    """A table of treelet builds: scene, the JSON fields `columns` (key, width), build ms
    (min/median/max), the treelet stages, dispatches and SAH."""
    print(f"{name}: scene, {title}, build ms (min/median/max), treelets ms, climb ms, dispatches, SAH")
    for r in rows(name):
        b = r.get("build_ms_spread") or {}
        st = r.get("stages_ms") or {}
        cells = " ".join(f"{r.get(key)!s:>{width}}" for key, width in columns)
        print(f"  {os.path.basename(r['scene'])[:14]:14} {cells} {b.get('min', 0):7.2f} {r['build_ms']:7.2f}"
              f" {b.get('max', 0):7.2f} {st.get('treelets') or 0:7.3f} {st.get('treelets climb') or 0:6.3f}"
              f" {r['dispatches']:4} {r.get('sah') or 0:.4f}")
round_rows("subtrees.jsonl", "builder, subtree levels, width, level dispatches asked",
           [("builder", 11), ("subtree_levels", 2), ("subtree_width", 4), ("level_dispatches", 4)])
round_rows("phases.jsonl", "builder, rounds, phases, first round's, teams below, DP, root slots",
           [("builder", 11), ("rounds", 2), ("phases", 4), ("first_round_phases", 4), ("team_below", 10),
            ("treelet_dp", 8), ("root_slots", 9)])
print("phases_profile.jsonl: scene, per kernel: dispatches and ms in all; then each phase's roots_phase + treelets_optimize ms")
for r in rows("phases_profile.jsonl"):
    totals = {}
    for d in r.get("dispatch_ms") or []:
        n, ms = totals.get(d["kernel"], (0, 0.0))
        totals[d["kernel"]] = (n + 1, ms + d["ms"])
    print(f"  {os.path.basename(r['scene'])[:14]:14} " + ", ".join(f"{k} {n}x {ms:.3f}" for k, (n, ms) in totals.items()))
    walks = [d["ms"] for d in r.get("dispatch_ms") or [] if d["kernel"] == "roots_phase"]
    treelets = [d["ms"] for d in r.get("dispatch_ms") or [] if d["kernel"] == "treelets_optimize"]
    print("    " + " ".join(f"{w:.3f}+{t:.3f}" for w, t in zip(walks, treelets)))
round_rows("teams.jsonl", "overlap, teams below (levels), (climb)",
           [("round_overlap", 4), ("team_below", 5), ("climb_team_below", 3)])
print("indirect.jsonl: scene, builder, layout, indirect validation, turn, build ms (min/median/max), wide ms,"
      " dispatches, SAH")
for r in rows("indirect.jsonl"):
    b = r.get("build_ms_spread") or {}
    print(f"  {os.path.basename(r['scene'])[:14]:14} {r['builder']:11} {r.get('layout')!s:6} {r['indirect_validation']}"
          f" {r['turn']} {b.get('min', 0):7.2f} {r['build_ms']:7.2f} {b.get('max', 0):7.2f}"
          f" {(r.get('stages_ms') or {}).get('wide') or 0:6.3f} {r['dispatches']:4} {r.get('sah') or 0:.4f}")
print("widelevels.jsonl: scene, wide levels, level dispatches asked, wide stage ms, build ms")
for r in rows("widelevels.jsonl"):
    print(f"  {os.path.basename(r['scene'])[:14]:14} {r.get('wide_levels') or 0:3} {r.get('wide_level_dispatches')!s:>4}"
          f" {(r.get('stages_ms') or {}).get('wide') or 0:7.3f} {r['build_ms']:7.2f}")
for name in ("scaling.jsonl", "baseline.jsonl"):
    print(f"{name}: scene, builder, triangles, build ms (min/median/max), Mtris/s, stages ms, SAH")
    for r in rows(name):
        st = " ".join(f"{k} {v:.2f}" for k, v in (r.get("stages_ms") or {}).items() if v is not None)
        b = r.get("build_ms_spread") or {}
        last = r.get("last_round_size")
        preset = (f"({r['treelet_size']},{r['rounds']}" + (f",{last}" if last and last != r["treelet_size"] else "")
                  + ")") if r.get("treelet_size") else ""
        print(f"  {os.path.basename(r['scene'])[:14]:14} {r['builder']:11} {preset:8} {r['triangles']:>9}"
              f" {b.get('min', 0):7.2f} {r['build_ms']:7.2f} {b.get('max', 0):7.2f}"
              f" {r.get('mtris_per_s') or 0:7.1f}  {st}  {r.get('sah') or 0:.4f}")
        tuning = r.get("schedule_tuning")
        if tuning:
            kept = [t for t in tuning["trials"] if t["adopted"]]
            first = tuning["trials"][0] if tuning["trials"] else {}
            print(f"      tuned in {tuning['builds']} builds, {tuning['wall_ms']:.0f} ms: {tuning['kept']}"
                  f" (first comparison's default {first.get('kept_ms') or 0:.3f} ms,"
                  f" last kept {(kept[-1]['candidate_ms'] if kept else first.get('kept_ms')) or 0:.3f} ms)"
                  + (" REFUSED: " + ", ".join(t["schedule"] + (f" ({t['error']})" if t.get("error") else " (other tree)")
                                              for t in tuning["trials"] if t["other_tree"] or t.get("error"))
                     if any(t["other_tree"] or t.get("error") for t in tuning["trials"]) else ""))
PY
for f in kernelstats probe variants layouts stress profile kernels schedules; do
  echo "--- $f (tail)"
  tail -n 40 $res/$f.txt 2>/dev/null
done
save
