#!/usr/bin/env bash
# The distributed run (issue 19), suite 'mpi': frontdt-mpi under mpirun
# with 1, 2, 3, 4 and 7 ranks (oversubscribed on a small machine) on
# tests/gen_points families (a lattice, clusters, an extruded 2-D grid,
# duplicates, uniform) and the real sets in ../shared/data (skipped when
# absent): the set hash equals the serial run's, every message kind's sent
# total equals its received total and FACERECV = FACESEND; -o gathers the
# same mesh as the serial run's, byte for byte; a rank that fails (the
# hidden --inject-failure) ends every rank with the error, no hang, no
# output; -o BASE.pvtu writes one piece a rank and an index that VTK reads
# as the serial mesh.
# Usage: test_mpi.sh FRONTDT FRONTDT_MPI GEN_POINTS MPIRUN DATA_DIR [PYTHON3]
set -u
frontdt=$1 fmpi=$2 gen=$3 mpirun=$4 data=$5 python=${6:-python3}
pvtu_check=$(dirname "$0")/pvtu_check.py
if [[ $(id -u) -eq 0 ]]; then
  # Open MPI refuses root unless told
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fi
work=$(mktemp -d "${TMPDIR:-/tmp}/fdt-test-mpi.XXXXXX")
trap 'rm -rf "$work"' EXIT
fails=0
checks=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

# Open MPI wants --oversubscribe for more ranks than cores; MPICH's
# launcher (hydra) oversubscribes as it is and refuses the flag.
oversub=()
"$mpirun" --version 2>&1 | grep -q "Open MPI" && oversub=(--oversubscribe)

# mpirun with NP ranks, a time limit (a hang is a failure, not a stall).
mpi() {
  local np=$1 limit=$2
  shift 2
  timeout -k 5 "$limit" "$mpirun" "${oversub[@]}" -np "$np" "$@"
}

# check NAME FILE NPS...: the hash and the message balance for each count
# (frontdt-mpi gets the options in the array extra too).
extra=()
check() {
  local name=$1 f=$2
  shift 2
  local ref
  ref=$("$frontdt" --mode serial -q --set-hash "$f" | sed -n 's/^set-hash: //p')
  [[ -n $ref ]] || { fail "$name: no serial set hash"; return; }
  for np in "$@"; do
    checks=$((checks + 1))
    local out="$work/out.$np" err="$work/err.$np"
    mpi "$np" 300 "$fmpi" -q --set-hash --stats "${extra[@]}" "$f" >"$out" 2>"$err"
    local rc=$?
    if [[ $rc -ne 0 ]]; then
      fail "$name, $np ranks: exit $rc"; sed 's/^/    /' "$err" | tail -20; continue
    fi
    local got
    got=$(sed -n 's/^set-hash: //p' "$out")
    [[ $got == "$ref" ]] || fail "$name, $np ranks: set hash $got, serial $ref"
    # "    KIND   sent / received" of the totals, one line per kind
    local kinds
    kinds=$(awk '/sent \/ received \(all ranks\)/ {t = 1; next}
                 t && NF == 4 && $3 == "/" {print $1, $2, $4}' "$err")
    [[ $(wc -l <<<"$kinds") -eq 6 ]] || { fail "$name, $np ranks: no message totals"; continue; }
    while read -r kind s r; do
      [[ $s == "$r" ]] || fail "$name, $np ranks: $kind sent $s, received $r"
    done <<<"$kinds"
    local fs fr
    fs=$(awk '$1 == "FACESEND" {print $2}' <<<"$kinds")
    fr=$(awk '$1 == "FACERECV" {print $2}' <<<"$kinds")
    [[ $fs == "$fr" ]] || fail "$name, $np ranks: FACESEND $fs, FACERECV $fr"
    if [[ $np -gt 1 && $fs -eq 0 ]]; then
      fail "$name, $np ranks: no FACESEND at all (is it distributed?)"
    fi
    # the per-rank times: a row per rank, faces advanced summing to > 0
    local rows
    rows=$(awk '/front s +cpu s/ {t = 1; next} t && NF == 7 {n++; f += $6} t && NF != 7 {t = 0}
                END {print n + 0, f + 0}' "$err")
    [[ ${rows%% *} -eq $np && ${rows##* } -gt 0 ]] ||
      fail "$name, $np ranks: per-rank times '$rows'"
  done
}

nps=(1 2 3 4 7)
for fam in "lattice 3000" "clusters 3000" "grid2d 3000" "dup 4000" "uniform 4000"; do
  set -- $fam
  "$gen" "$1" "$2" 19 "$work/$1.xyz" >/dev/null || { fail "gen_points $1"; continue; }
  check "$1" "$work/$1.xyz" "${nps[@]}"
done
# A face waiting for each answer (--no-park, message mode's loop) gives the
# same mesh as parked faces.
extra=(--no-park)
check "clusters --no-park" "$work/clusters.xyz" 2 3
check "uniform --no-park" "$work/uniform.xyz" 4
extra=()
# Fewer points than ranks have parts for: empty parts take part in the
# termination as non-roots.
printf '0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n' >"$work/five.xyz"
check five "$work/five.xyz" 7

if [[ -r $data/bunny_35947.xyz ]]; then
  check bunny "$data/bunny_35947.xyz" "${nps[@]}"
else
  echo "skip: $data/bunny_35947.xyz absent"
fi
if [[ -r $data/autzen_lidar_110000.xyz ]]; then
  check autzen "$data/autzen_lidar_110000.xyz" 2 3 4
else
  echo "skip: $data/autzen_lidar_110000.xyz absent"
fi

# -o: the gathered mesh is the serial run's, in every format's bytes (the
# canonical .tets; .vtu carries the input numbering and the hull).
"$frontdt" --mode serial -q -o "$work/ref.tets" "$work/clusters.xyz" || fail "serial -o"
"$frontdt" --mode serial -q -o "$work/ref.vtu" "$work/clusters.xyz" || fail "serial -o vtu"
for np in 1 3; do
  checks=$((checks + 1))
  mpi "$np" 120 "$fmpi" -q -o "$work/m$np.tets" "$work/clusters.xyz" || fail "-o .tets, $np ranks"
  cmp -s "$work/ref.tets" "$work/m$np.tets" || fail "-o .tets, $np ranks: differs from serial"
done
checks=$((checks + 1))
mpi 4 120 "$fmpi" -q -o "$work/m4.vtu" "$work/clusters.xyz" || fail "-o .vtu, 4 ranks"
[[ -s $work/m4.vtu ]] || fail "-o .vtu, 4 ranks: no file"
# .ele needs neighbours, not gathered yet: refused before anything runs
checks=$((checks + 1))
mpi 2 60 "$fmpi" -q -o "$work/m.ele" "$work/clusters.xyz" 2>/dev/null
[[ $? -eq 1 && ! -e $work/m.node ]] || fail ".ele not refused with exit 1"

# -o BASE.pvtu: one .vtu piece a rank and the index, read back through VTK
# (pvtu_check.py; skipped without python3 VTK) against the serial tets.
checks=$((checks + 1))
mkdir -p "$work/pv"
if mpi 3 120 "$fmpi" -q -o "$work/pv/mesh.pvtu" "$work/clusters.xyz"; then
  for f in mesh.pvtu mesh_0.vtu mesh_1.vtu mesh_2.vtu; do
    [[ -s $work/pv/$f ]] || fail ".pvtu, 3 ranks: no $f"
  done
  [[ $(grep -c '<Piece Source="mesh_[0-2].vtu"/>' "$work/pv/mesh.pvtu") -eq 3 ]] ||
    fail ".pvtu, 3 ranks: the index does not name the 3 pieces"
  "$python" "$pvtu_check" "$work/pv/mesh.pvtu" "$work/clusters.xyz" "$work/ref.tets"
  prc=$?
  [[ $prc -eq 0 || $prc -eq 77 ]] || fail ".pvtu, 3 ranks: VTK reads another mesh"
else
  fail "-o .pvtu, 3 ranks"
fi
# a piece that cannot be written: exit 5, no piece and no index left
checks=$((checks + 1))
mpi 2 60 "$fmpi" -q -o "$work/none/mesh.pvtu" "$work/clusters.xyz" 2>/dev/null
rc=$?
[[ $rc -eq 5 && ! -e $work/none ]] || fail ".pvtu into a missing directory: exit $rc"

# A failing rank: every rank ends with the error (exit 7), quickly, and
# nothing is written. The wrapper reports each rank's exit code and exits
# 0 itself, so mpirun does not kill the other ranks first: each must end
# on its own (the ABORT reached it).
rankvar='${OMPI_COMM_WORLD_RANK:-${PMI_RANK:-?}}'
for spec in "4 2:50" "7 0:200" "3 1:0" "2 1:400"; do
  set -- $spec
  np=$1 inj=$2
  checks=$((checks + 1))
  rm -f "$work"/fail.tets "$work"/.fail.tets.tmp.*
  out=$(mpi "$np" 60 bash -c "\"\$0\" -q --inject-failure $inj -o \"$work/fail.tets\" \"$work/uniform.xyz\"; echo \"rank-exit $rankvar \$?\"" "$fmpi" 2>"$work/ferr")
  rc=$?
  [[ $rc -eq 0 ]] || fail "injected $inj on $np ranks: mpirun exit $rc (a hang or a crash)"
  n7=$(grep -c '^rank-exit [0-9?]* 7$' <<<"$out")
  [[ $n7 -eq $np ]] || { fail "injected $inj on $np ranks: $n7 of $np ranks ended with exit 7"; echo "$out"; }
  grep -q "rank ${inj%%:*} failed" "$work/ferr" || { fail "injected $inj: no message naming the rank"; cat "$work/ferr"; }
  ls -A "$work" | grep -q fail.tets && fail "injected $inj on $np ranks: output left behind"
done

echo "$checks checks, $fails failures"
[[ $fails -eq 0 ]]
