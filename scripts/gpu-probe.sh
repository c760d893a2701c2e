#!/usr/bin/env bash
# Where a treelet level's time goes on a GPU: an experiment, not a builder. On an H200 a level of
# a few treelets took 45-57 µs as a dispatch of its own (an empty dispatch 13 µs) and ~24 µs as a
# wave of the one-workgroup climb, and treelets by teams of 32 (the DP ~20x shorter) took as long
# as one invocation per treelet: the DP is not what a small level waits for. This script builds
# three variants of the treelet kernels that skip one more step each, all of which keep the LBVH
# (no treelet is written back, so every variant has the same levels and dispatches), and times
# every level of each as a dispatch of its own:
#   nowrite  formation and DP, no write-back;
#   nodp     formation only (the DP replaced by a constant);
#   noform   the root's cost and the treelet's first two leaves only.
# nowrite - nodp is the DP's latency per level (nowrite is also run with teams of 32 for every
# treelet and with the DP's loop form), nodp - noform the formation's expansions, noform minus an
# empty dispatch what every treelet dispatch costs besides (launch, first loads, next levels). The variants differ from the real kernel by conditions on `params.zero` (always 0, a
# uniform the compiler cannot fold), so the rest of each kernel is compiled as it is.
#   Here, after `bash ../shared/gpu/pack.sh`:   bash scripts/gpu-probe.sh build
#     (three incremental release builds; each variant's binary goes to .gpu/probe-NAME.xz, and
#     the treelet includes are restored after each, also on failure)
#   On the GPU (`run` with carry [".gpu", ".gl"]):   bash scripts/gpu-probe.sh run
#     (or as the "probe" step of scripts/gpu-all.sh, which runs it when the binaries are there)
#   A dry run of `run` on lavapipe, after `build`: TREELET=target/release/treelet SCENES=field:50 \
#     REPEATS=1 bash scripts/gpu-probe.sh run
# Output: $OUT/probe.jsonl and a table of every variant's level times, round by round.
set -eu
dp=shaders/include/treelet_dp.wgsl
team=shaders/include/treelet_team.wgsl
case "${1:-}" in
build)
  [ -f "$HOME/.cargo/env" ] && . "$HOME/.cargo/env"
  # Restoring checks the two includes out: refuse to start with changes there to lose.
  git diff --quiet -- $dp $team || { echo "uncommitted changes in $dp or $team: commit or stash them first"; exit 1; }
  mkdir -p .gpu
  trap 'git checkout -- $dp $team' EXIT
  nowrite='s/    if treelet_leaves > 2u \&\& full_cost < current {/    if treelet_leaves > 2u \&\& full_cost < current \&\& params.zero != 0u {/'
  nodp='s/    var best = subset_costs();/    var best = vec2<u32>(1u, 0u); if params.zero != 0u { best = subset_costs(); }/'
  noform='s/    for (var count = 2u; count < TREELET_SIZE; count++) {/    for (var count = 2u; count < TREELET_SIZE \&\& params.zero != 0u; count++) {/'
  for variant in nowrite nodp noform; do
    case $variant in
      nowrite) edits=("$nowrite") ;;
      nodp) edits=("$nowrite" "$nodp") ;;
      noform) edits=("$nowrite" "$nodp" "$noform") ;;
    esac
    git checkout -- $dp $team
    for edit in "${edits[@]}"; do sed -i "$edit" $dp; done
    # The teams' write-back too (treelet_team.wgsl), so that teams keep the LBVH as well.
    sed -i "$nowrite" $team
    # Each substitution must have matched (one line each).
    [ "$(git diff --numstat -- $dp | cut -f1) $(git diff --numstat -- $team | cut -f1)" = "${#edits[@]} 1" ] \
      || { echo "probe $variant: a substitution did not match $dp or $team"; exit 1; }
    cargo build --release --quiet
    strip -o /tmp/treelet-probe target/release/treelet
    xz -T2 -6 -c /tmp/treelet-probe > .gpu/probe-$variant.xz
    echo "probe $variant: .gpu/probe-$variant.xz"
  done
  git checkout -- $dp $team
  cargo build --release --quiet
  ;;
run)
  . scripts/gpu-env.sh
  probes=/tmp/treelet-probes
  mkdir -p "$probes"
  for f in .gpu/probe-*.xz; do
    [ -f "$f" ] || { echo "no .gpu/probe-*.xz: run 'bash scripts/gpu-probe.sh build' first"; exit 1; }
    name=$(basename "$f" .xz)
    xz -dc "$f" > "$probes/${name#probe-}" && chmod +x "$probes/${name#probe-}"
  done
  : > "$out/probe.jsonl"
  for s in ${SCENES:-conference sibenik}; do
    # nowrite also with the DP's other forms: teams of 32 for every treelet, and the loop form.
    for row in real nowrite nowrite:--team-below=1000000000 nowrite:--treelet-dp=loop nodp noform; do
      variant=${row%%:*}
      opts=""
      [ "$row" != "$variant" ] && opts=${row#*:}
      exe=$probes/$variant
      [ $variant = real ] && exe=$bin
      [ -x "$exe" ] || continue
      # shellcheck disable=SC2086
      timeout 100 "$exe" bench --scene "$s" --builder trbvh --level-dispatches 32 --profile-dispatches \
        --width 64 --height 64 --spp 1 --repeats "${REPEATS:-5}" ${opts/=/ } 2>> "$out/probe.log" \
        | sed "s/^{/{\"probe\":\"$variant${opts:+ $opts}\",/" >> "$out/probe.jsonl" \
        || echo "$s $row: exit $? (see probe.log)"
    done
  done
  python3 - "$out/probe.jsonl" <<'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
for scene in dict.fromkeys(r["scene"] for r in rows):
    print(f"\n{scene}: ms per treelet dispatch, round by round (| starts a round), build ms")
    for r in (r for r in rows if r["scene"] == scene):
        d = [x for x in r["dispatch_ms"] if x["stage"].startswith("treelets")]
        small = [x["ms"] or 0 for x in d if x["kernel"] == "treelets_optimize" and (x["ms"] or 0) < 0.08]
        print(f"  {r['probe']:35} build {r['build_ms']:7.3f}  levels under 0.08 ms: {len(small)}, median "
              f"{statistics.median(small) if small else 0:.4f}  sah {r['sah']:.4f}")
        print("    " + " ".join(("|" if x["kernel"] == "nodes_level" else "") + f"{x['ms'] or 0:.3f}" for x in d))
PY
  ;;
*)
  echo "usage: bash scripts/gpu-probe.sh build|run"
  exit 1
  ;;
esac
