#!/usr/bin/env bash
# The GPU check: on a machine with a GPU (or lavapipe) and lobelight built, runs the tests that
# need a device and the benchmarks of the model scenes, of 10 M-splat clouds (diffuse and
# glossy) and of a dense cloud in a large room, and writes one JSON with the adapter's name,
# each step's status and time and each benchmark's report.
#
#   benches/gpu-check.sh [--quick] [--no-tests | --no-benches] [-o FILE]
#                                                            (default FILE: gpu-check.json)
#
#   --quick     small sizes (the default box at 20 k photons and 4 × 4 gather rays, a 100 k
#               cloud): under a minute on lavapipe, which is how the script itself is tested
#   --no-tests  benchmarks only
#   --no-benches  the tests only (a short lease: run the benchmarks first, then the tests)
#
# Environment:
#   LOBELIGHT        the binary (default: target/release/lobelight, built by `cargo build --release`)
#   LOBELIGHT_TESTS  a folder of built test executables to run (a machine without cargo);
#                    without it the device tests run through `cargo test --release`
#   STEP_TIMEOUT     seconds any one step may take before it is stopped and marked so (default 240)
#
# The full check wants scenes/models/fetch.sh run first (the bunny and the dragons); a scene
# whose model is missing is recorded as skipped, never as passed.
set -uo pipefail

quick=0
tests=1
benches=1
out=gpu-check.json
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --no-tests) tests=0 ;;
    --no-benches) benches=0 ;;
    -o) out="$2"; shift ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    *) echo "gpu-check: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done

root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root" || exit 2
bin="${LOBELIGHT:-$root/target/release/lobelight}"
if [ ! -x "$bin" ]; then
  echo "gpu-check: no lobelight binary at $bin (cargo build --release, or set LOBELIGHT)" >&2
  exit 2
fi
step_timeout="${STEP_TIMEOUT:-240}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Each step's record, one JSON member a line, joined at the end.
steps=()

# json_string TEXT: TEXT as a JSON string (quotes, backslashes and control characters escaped).
json_string() {
  local s=${1//\\/\\\\}
  s=${s//\"/\\\"}
  s=${s//$'\n'/\\n}
  s=${s//$'\t'/\\t}
  s=$(printf '%s' "$s" | tr -d '\000-\037')
  printf '"%s"' "$s"
}

# run_step NAME COMMAND...: runs a step under the step timeout; records its status, seconds and,
# when it printed a JSON report on stdout, the report.
run_step() {
  local name=$1
  shift
  local start end rc status report
  echo "gpu-check: $name" >&2
  start=$(date +%s.%N)
  timeout "$step_timeout" "$@" >"$work/$name.out" 2>"$work/$name.err"
  rc=$?
  end=$(date +%s.%N)
  case $rc in
    0) status=ok ;;
    124) status=timeout ;;
    *) status=failed ;;
  esac
  report=null
  if [ $rc = 0 ] && head -c 1 "$work/$name.out" | grep -q '[{[]'; then
    report=$(cat "$work/$name.out")
  fi
  local seconds
  seconds=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", b - a }')
  local tail=""
  if [ $rc != 0 ]; then
    # A failing test prints its panic on stdout (libtest), a failing command on stderr.
    tail=$(cat "$work/$name.out" "$work/$name.err" | grep -v '^test .* \.\.\. ok$' | tail -c 3000)
    echo "gpu-check: $name $status ($seconds s):" >&2
    printf '%s\n' "$tail" | tail -n 30 >&2
  fi
  steps+=("$(json_string "$name"): {\"status\": \"$status\", \"seconds\": $seconds, \"error\": $(json_string "$tail"), \"report\": $report}")
  write_report
}

skip_step() {
  echo "gpu-check: $1 skipped: $2" >&2
  steps+=("$(json_string "$1"): {\"status\": \"skipped\", \"seconds\": 0, \"error\": $(json_string "$2"), \"report\": null}")
  write_report
}

# write_report: the JSON so far, rewritten after every step, so that a check stopped from outside
# still leaves the steps it finished.
write_report() {
  {
    printf '{\n  "adapter": %s,\n  "backend": %s,\n  "quick": %s,\n' \
      "$adapter" "${backend:-null}" "$([ $quick = 1 ] && echo true || echo false)"
    printf '  "date": %s,\n  "cpu": %s,\n  "steps": {\n' "$(json_string "$(date -u +%FT%TZ)")" \
      "$(json_string "$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)")"
    n=${#steps[@]}
    for i in "${!steps[@]}"; do
      sep=,
      [ $((i + 1)) = "$n" ] && sep=
      printf '    %s%s\n' "${steps[$i]}" "$sep"
    done
    printf '  }\n}\n'
  } >"$out"
}

"$bin" info scenes/cornell.toml --json >"$work/info.json" 2>"$work/info.err"
adapter=$(sed -n 's/^  "adapter": \(".*"\),$/\1/p' "$work/info.json")
backend=$(sed -n 's/^  "backend": \(".*"\),$/\1/p' "$work/info.json")
if [ -z "$adapter" ]; then
  echo "gpu-check: no adapter: $(cat "$work/info.err")" >&2
  exit 1
fi
if [ "$adapter" = '"cpu mirror"' ]; then
  echo "gpu-check: no GPU adapter (lobelight would run on the CPU mirror): $(cat "$work/info.err")" >&2
  exit 1
fi
echo "gpu-check: adapter $adapter ($backend)" >&2

# The tests that open a device (each integration test that calls common::gpu(), but the
# viewer's, which needs a window system).
device_tests=(trace photons bins deposits em estimate_coverage final_gather grid_parity direct path
  tone paging skip stress photon_view reference render sweep fit_groups)
if [ $tests = 1 ]; then
  if [ -n "${LOBELIGHT_TESTS:-}" ]; then
    for t in "${device_tests[@]}"; do
      exe=$(ls "$LOBELIGHT_TESTS/$t" "$LOBELIGHT_TESTS/$t"-* 2>/dev/null | head -n 1)
      if [ -n "$exe" ]; then
        run_step "test_$t" "$exe"
      else
        skip_step "test_$t" "no executable for $t in $LOBELIGHT_TESTS"
      fi
    done
  elif command -v cargo >/dev/null; then
    args=()
    for t in "${device_tests[@]}"; do args+=(--test "$t"); done
    run_step tests cargo test --release --no-fail-fast "${args[@]}"
  else
    skip_step tests "neither cargo nor LOBELIGHT_TESTS"
  fi
fi

if [ $benches = 0 ]; then
  scenes=()
elif [ $quick = 1 ]; then
  scenes=(scenes/cornell.toml)
  photons=(--photons 20000 --gather 4)
  sizes=100000
  cluster=(--cluster-splats 20000 --photons 20000 --gather 4)
  # Frames with the temporal pass timed, and an orbit of two frames (its keys, not its figure).
  frame=(--taa --orbit 2)
else
  # The box against the models whose bake the box's tuning does not predict.
  scenes=(scenes/cornell.toml scenes/bunny.toml scenes/dragon_full.toml)
  photons=()
  sizes=1000000,10000000
  cluster=()
  frame=(--taa)
fi
for scene in "${scenes[@]}"; do
  name=$(basename "$scene" .toml)
  if ! "$bin" info "$scene" >/dev/null 2>"$work/load.err"; then
    for what in photons em frame; do skip_step "${what}_$name" "$(cat "$work/load.err")"; done
    continue
  fi
  # --gpu: the device's figures, also where it is a software rasterizer (whose bakes the
  # benchmarks would otherwise run on the CPU mirror).
  for what in photons em; do
    run_step "${what}_$name" "$bin" bench "$what" "$scene" "${photons[@]}" --gpu --json
  done
  run_step "frame_$name" "$bin" bench frame "$scene" "${photons[@]}" "${frame[@]}" --gpu --json
done
if [ $benches = 1 ]; then
  for material in diffuse glossy; do
    run_step "scale_$material" "$bin" bench scale --sizes "$sizes" --material "$material" \
      -o "$work/scale_$material" --gpu --json
  done
  run_step cluster "$bin" bench cluster "${cluster[@]}" -o "$work/cluster" --gpu --json
fi

write_report
echo "gpu-check: wrote $out" >&2
failed=$(grep -c '"status": "\(failed\|timeout\)"' "$out")
[ "$failed" = 0 ]
