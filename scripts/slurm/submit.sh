#!/usr/bin/env bash
# Submit an `occgt build` as three Slurm jobs (docs/SCALE.md):
#   1. select: array of NTASKS tasks, task k selects the sorted scenes i with i % NTASKS == k;
#   2. write:  array of NTASKS tasks after every select task succeeded (afterok), task k
#              writes the shards s with s % NTASKS == k (writing needs every scene's selection);
#   3. merge:  one job after every write task succeeded: checks every shard, writes the indices.
# A failed task cancels what depends on it (--kill-on-invalid-dep=yes); re-submitting the same
# command redoes only the scenes and shards that are not complete.
#
#   scripts/slurm/submit.sh RECIPE OUT NTASKS
#
# Prints "select=<id> write=<id> merge=<id>" on stdout. Environment:
#   OCCGT_BIN            occgt binary every node can run (default: occgt on PATH, else this
#                        checkout's build/apps/occgt); made absolute
#   OCCGT_CPUS_PER_TASK  CPUs (= TBB threads) per task (default 1)
#   OCCGT_SLURM_LOGS     folder of the job logs (default OUT/slurm-logs)
#   OCCGT_SBATCH_ARGS    extra sbatch flags for all three jobs, e.g. "--partition=cpu --time=4:00:00"
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
die() { echo "submit.sh: $*" >&2; exit 2; }
[[ $# == 3 ]] || die "usage: submit.sh RECIPE OUT NTASKS"
[[ -f "$1" ]] || die "recipe '$1': no such file"
[[ "$3" =~ ^[1-9][0-9]*$ ]] || die "NTASKS '$3': expected an integer >= 1"
recipe="$(realpath "$1")"
out="$(realpath -m "$2")"
ntasks="$3"
command -v sbatch >/dev/null || die "sbatch not found (install slurm-client or load the Slurm module)"

max_array="$(scontrol show config 2>/dev/null | sed -n 's/^MaxArraySize *= *\([0-9]*\).*/\1/p')"
if [[ -n "$max_array" ]] && ((ntasks > max_array)); then
  die "NTASKS $ntasks exceeds the cluster's MaxArraySize $max_array (use fewer tasks)"
fi

bin="${OCCGT_BIN:-}"
if [[ -z "$bin" ]]; then
  bin="$(command -v occgt || true)"
  [[ -n "$bin" ]] || bin="$here/../../build/apps/occgt"
fi
[[ -x "$bin" ]] || die "occgt binary '$bin' not executable (set OCCGT_BIN)"
bin="$(realpath "$bin")"
cpus="${OCCGT_CPUS_PER_TASK:-1}"
[[ "$cpus" =~ ^[1-9][0-9]*$ ]] || die "OCCGT_CPUS_PER_TASK '$cpus': expected an integer >= 1"
logs="$(realpath -m "${OCCGT_SLURM_LOGS:-$out/slurm-logs}")"
mkdir -p "$logs"  # Slurm does not create the folder of --output

extra=()
[[ -n "${OCCGT_SBATCH_ARGS:-}" ]] && read -r -a extra <<<"$OCCGT_SBATCH_ARGS"
common=(--parsable --cpus-per-task="$cpus" --export="ALL,OCCGT_BIN=$bin" "${extra[@]}")
after() { echo "--dependency=afterok:$1" --kill-on-invalid-dep=yes; }
jobid() { local id; id="$(cat)"; echo "${id%%;*}"; }  # --parsable prints "id[;cluster]"

select_id="$(sbatch "${common[@]}" --array="0-$((ntasks - 1))" --job-name=occgt-select \
  --output="$logs/select-%A_%a.log" "$here/build.sbatch" "$recipe" "$out" select | jobid)"
# shellcheck disable=SC2046
write_id="$(sbatch "${common[@]}" $(after "$select_id") --array="0-$((ntasks - 1))" \
  --job-name=occgt-write --output="$logs/write-%A_%a.log" \
  "$here/build.sbatch" "$recipe" "$out" write | jobid)"
# shellcheck disable=SC2046
merge_id="$(sbatch "${common[@]}" $(after "$write_id") --job-name=occgt-merge \
  --output="$logs/merge-%j.log" "$here/merge.sbatch" "$out" | jobid)"
echo "select=$select_id write=$write_id merge=$merge_id"
