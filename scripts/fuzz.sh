#!/usr/bin/env bash
# Build and run the libFuzzer targets (tests/fuzz, docs/RELIABILITY.md "Fuzzing").
#
#   scripts/fuzz.sh                 every target, 20000 executions each (the default)
#   scripts/fuzz.sh --smoke         every target, 2000 executions each (a quick check)
#   scripts/fuzz.sh --runs N        every target, N executions each
#   scripts/fuzz.sh --seconds S     every target, at most S seconds each (no run limit)
#   scripts/fuzz.sh --only NAME     only fuzz_NAME (may be repeated), with any of the above
#
# The targets run OCCGT_FUZZ_JOBS at a time (default: the cores, at most 2), one core each;
# the summary lines come in target order.
#
# Installs clang-14 and libclang-rt-14-dev when missing (idempotent), configures
# build-fuzz/ with clang, ASan + UBSan and -DOCCGT_BUILD_FUZZ=ON, builds only the fuzz
# targets (gt_core and gt_io; fuzz_recipe links gt_pipeline and so the layers below it,
# the PCL/OctoMap sources included), builds each target's
# seed corpus from ../shared/data and tests/fixtures (tests/fuzz/make_seeds.py), runs
# each target on its corpus and exits non-zero when any target crashes, leaks, hits UB,
# times out or runs out of memory. The corpus grows in build-fuzz/corpus/<target>/; crash
# inputs are written to build-fuzz/artifacts/<target>/. A summary line per target gives
# executions, coverage (cov: edges, ft: features) and the corpus size.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# ccache paths relative to the checkout, as in setup.sh.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$here}" CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-1}"

runs=20000
seconds=0
only=()
while (($#)); do
  case "$1" in
    --smoke) runs=2000 ;;
    --runs) runs="$2"; shift ;;
    --seconds) seconds="$2"; runs=0; shift ;;
    --only) only+=("$2"); shift ;;
    *) echo "fuzz.sh: unknown argument '$1' (expected --smoke, --runs N, --seconds S, --only NAME)" >&2
       exit 2 ;;
  esac
  shift
done

# Toolchain: clang and its sanitizer/libFuzzer runtimes from Debian.
missing=()
for p in clang-14 libclang-rt-14-dev; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "fuzz.sh: installing ${missing[*]}" >&2
  sudo_cmd=()
  [[ $(id -u) == 0 ]] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
# The project's own build dependencies (and python3-numpy/PIL for the seeds).
"$here/scripts/setup.sh" --test --no-build

build="${OCCGT_FUZZ_BUILD_DIR:-$here/build-fuzz}"
# Configured every time (quick when nothing changed), so a tree from an earlier version of
# this script gets the current flags. Unity batches (CMAKE_UNITY_BUILD) as in the sanitizer
# trees (scripts/test-sanitize; docs/RELIABILITY.md "CI time").
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_UNITY_BUILD=ON \
  -DOCCGT_SANITIZE=address,undefined -DOCCGT_BUILD_FUZZ=ON -DOCCGT_BUILD_BENCH=OFF -DOCCGT_BUILD_PYTHON=OFF >/dev/null
jobs="${OCCGT_FUZZ_JOBS:-$(nproc)}"
((jobs > 2)) && jobs=2
cmake --build "$build" --target fuzz_all -j "$jobs" >&2

targets=()
for exe in "$build"/tests/fuzz/fuzz_*; do
  [[ -x $exe ]] || continue
  name="$(basename "$exe")"
  if ((${#only[@]})); then
    keep=0
    for o in "${only[@]}"; do [[ $name == "fuzz_$o" || $name == "$o" ]] && keep=1; done
    ((keep)) || continue
  fi
  targets+=("$name")
done
((${#targets[@]})) || { echo "fuzz.sh: no fuzz targets built in $build/tests/fuzz" >&2; exit 1; }

# Seeds from the real samples (never committed) and the fixtures, rebuilt every run;
# the corpus folders keep what earlier runs found.
seeds="$build/seeds"
rm -rf "$seeds"
/usr/bin/python3 "$here/tests/fuzz/make_seeds.py" "$seeds" "$here/../shared/data" "$here" >&2

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:halt_on_error=1:abort_on_error=1:allocator_may_return_null=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
logs="$build/logs"
mkdir -p "$logs"
# run_target NAME: one target on its corpus; its output goes to $logs/<short>.log, its exit
# code to $logs/<short>.rc and its summary line to $logs/<short>.summary.
run_target() {
  local name="$1" short="${1#fuzz_}"
  local corpus="$build/corpus/$short" artifacts="$build/artifacts/$short/"
  mkdir -p "$corpus" "$artifacts"
  local limit=(-runs="$runs")
  ((seconds > 0)) && limit=(-max_total_time="$seconds")
  # Inputs up to the largest seed, between 64 KiB and 256 KiB: the real samples (npz
  # 72 KB, 7-Scenes depth PNG 90 KB) fit whole; a real 1.2 MB TartanAir .npy is cut,
  # which keeps its real header while each execution stays fast.
  local max_len
  max_len=$(find "$seeds/$short" -type f -printf '%s\n' | sort -n | tail -1)
  ((${max_len:-0} < 65536)) && max_len=65536
  ((max_len > 262144)) && max_len=262144
  local start rc=0
  start=$(date +%s)
  "$build/tests/fuzz/$name" "${limit[@]}" -max_len="$max_len" -timeout=20 -rss_limit_mb=3072 \
    -print_final_stats=1 -artifact_prefix="$artifacts" "$corpus" "$seeds/$short" \
    >"$logs/$short.log" 2>&1 || rc=$?
  local took=$(($(date +%s) - start)) stats execs
  stats="$(grep -E '^#[0-9]+.*(DONE|INITED|REDUCE|NEW|pulse)' "$logs/$short.log" | tail -1 || true)"
  execs="$(grep -E '^stat::number_of_executed_units' "$logs/$short.log" | awk '{print $2}' || true)"
  echo "fuzz.sh: $name rc=$rc ${took}s execs=${execs:-?} ${stats#*	}" >"$logs/$short.summary"
  echo "$rc" >"$logs/$short.rc"
}
# The targets run $jobs at a time (each is one process on one core); the summaries are
# printed in target order.
rm -f "$logs"/*.rc "$logs"/*.summary
running=0
for name in "${targets[@]}"; do
  if ((running >= jobs)); then
    wait -n || true
    running=$((running - 1))
  fi
  run_target "$name" &
  running=$((running + 1))
done
wait || true
failed=()
for name in "${targets[@]}"; do
  short="${name#fuzz_}"
  cat "$logs/$short.summary" >&2 2>/dev/null || echo "fuzz.sh: $name did not report" >&2
  rc="$(cat "$logs/$short.rc" 2>/dev/null || echo 1)"
  if ((rc != 0)); then
    failed+=("$name")
    grep -E 'ERROR|SUMMARY|unexpected|does not name|Test unit written' "$logs/$short.log" | head -8 >&2 || true
  fi
done

if ((${#failed[@]})); then
  echo "fuzz.sh: FAILED: ${failed[*]} (logs in $logs, inputs in $build/artifacts)" >&2
  exit 1
fi
echo "fuzz.sh: ${#targets[@]} targets, no crash (logs in $logs)" >&2
