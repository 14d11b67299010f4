#!/usr/bin/env bash
# A randomised sweep of the distributed run (issue 34), suite 'mpi': COUNT
# cases, each a tests/gen_points family at a random size (500-20,000
# points) and seed on a random rank count (1-8, oversubscribed), every
# family gen_points lists eligible. Each case's set hash must equal the
# serial run's, with exit 0. .ci/run also runs it in the ASan build, where
# a read out of bounds on any rank fails the case.
# The sweep's seed is printed first; FDT_SWEEP_SEED=S repeats a sweep.
# Usage: test_mpi_sweep.sh FRONTDT FRONTDT_MPI GEN_POINTS MPIRUN [COUNT]
set -u
frontdt=$1 fmpi=$2 gen=$3 mpirun=$4 count=${5:-12}
if [[ $(id -u) -eq 0 ]]; then
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fi
# Open MPI's own allocations outlive MPI_Finalize: LeakSanitizer would
# report them on every rank; out-of-bounds reads are still fatal.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0}
work=$(mktemp -d "${TMPDIR:-/tmp}/fdt-test-mpi-sweep.XXXXXX")
trap 'rm -rf "$work"' EXIT
oversub=()
"$mpirun" --version 2>&1 | grep -q "Open MPI" && oversub=(--oversubscribe)

seed=${FDT_SWEEP_SEED:-$(date +%s)}
echo "sweep seed $seed (FDT_SWEEP_SEED=$seed repeats it)"
RANDOM=$seed
mapfile -t families < <("$gen" --list | awk '{print $1}')
((${#families[@]} > 10)) || { echo "FAIL: gen_points --list gave ${#families[@]} families"; exit 1; }

fails=0
for ((i = 0; i < count; i++)); do
  fam=${families[RANDOM % ${#families[@]}]}
  n=$((500 + (RANDOM * 32768 + RANDOM) % 19501))
  pseed=$((RANDOM + 1))
  np=$((1 + RANDOM % 8))
  what="$fam $n (seed $pseed) on $np ranks"
  f="$work/in.xyz"
  "$gen" "$fam" "$n" "$pseed" "$f" >/dev/null || { echo "FAIL: gen_points $what"; fails=$((fails + 1)); continue; }
  ref=$("$frontdt" --mode serial -q --set-hash "$f" 2>"$work/serial.err" | sed -n 's/^set-hash: //p')
  if [[ -z $ref ]]; then
    echo "FAIL: $what: no serial set hash"; sed 's/^/    /' "$work/serial.err" | tail -5
    fails=$((fails + 1)); continue
  fi
  timeout -k 5 600 "$mpirun" "${oversub[@]}" -np "$np" "$fmpi" -q --set-hash "$f" \
    >"$work/mpi.out" 2>"$work/mpi.err"
  rc=$?
  got=$(sed -n 's/^set-hash: //p' "$work/mpi.out")
  if [[ $rc -ne 0 || $got != "$ref" ]]; then
    echo "FAIL: $what: exit $rc, set hash '$got', serial $ref"
    grep -m 5 -E 'ERROR|SUMMARY|#[0-9] ' "$work/mpi.err" | sed 's/^/    /'
    tail -3 "$work/mpi.err" | sed 's/^/    /'
    fails=$((fails + 1))
  else
    echo "ok: $what"
  fi
done
echo "$((count - fails)) of $count cases gave the serial set hash"
((fails == 0))
