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
# as the serial mesh; -o BASE.pfdtb / BASE.pele write a piece a rank and a
# text index (the pieces together: the serial tets, the collective .node
# the serial .node byte for byte; a failed piece leaves nothing). The distributed setup (each rank its slice of a text
# file, bisection by exchange, duplicates merged across slices): headers
# and comments, duplicates spread across slices, the whole-read fallback,
# standard input, a bad line in a later rank's slice (every rank exits 2
# with the serial run's message, line number included, and writes nothing).
# Every option both programs' --help list (one table, src/cli/options.c) is
# accepted by both with the same hashes, and frontdt-mpi's are documented.
# Usage: test_mpi.sh FRONTDT FRONTDT_MPI GEN_POINTS MPIRUN DATA_DIR [PYTHON3]
set -u
frontdt=$1 fmpi=$2 gen=$3 mpirun=$4 data=$5 python=${6:-python3}
pvtu_check=$(dirname "$0")/pvtu_check.py
if [[ $(id -u) -eq 0 ]]; then
  # Open MPI refuses root unless told
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fi
# In a sanitizer build: Open MPI's own allocations outlive MPI_Finalize,
# and LeakSanitizer would fail every rank on them; reads and writes out of
# bounds still end the rank with an error (.ci/run runs this suite so).
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0}
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
# A lattice turned 0.01 rad about a skew axis (issue 34): 40^3 of its
# points on 7 ranks crashed (the replica mesh's foreign apexes were read
# from the rank's own points, past their end); every rank count 1-8.
"$gen" skewlattice 64000 1 "$work/skewlattice.xyz" >/dev/null || fail "gen_points skewlattice"
check skewlattice "$work/skewlattice.xyz" 1 2 3 4 5 6 7 8
# The options frontdt-mpi shares with frontdt (issue 35): --quiet and
# --hash (gathered to rank 0) print what frontdt prints; --hash with a
# piece output is refused.
want=$("$frontdt" -q --hash "$work/skewlattice.xyz")
for np in 1 2 3; do
  checks=$((checks + 1))
  got=$(mpi "$np" 300 "$fmpi" --quiet --hash "$work/skewlattice.xyz" 2>"$work/q.err")
  [[ $got == "$want" && ! -s $work/q.err ]] ||
    fail "--quiet --hash, $np ranks: '$got' (frontdt: '$want'), stderr $(head -c 200 "$work/q.err")"
done
checks=$((checks + 1))
mpi 2 300 "$fmpi" -q --hash -o "$work/h.pvtu" "$work/skewlattice.xyz" >/dev/null 2>"$work/q.err" &&
  fail "--hash with a piece output was accepted"
grep -q -- "--hash gathers the mesh to rank 0" "$work/q.err" || fail "--hash with pieces: no message"
# Every option both programs accept (issue 35: one table, src/cli/options.c),
# as their --help lists it, short and long: given to frontdt and to
# frontdt-mpi on 2 ranks, with a value where the help names one, both
# accept it and print the same hashes (-o: the same file). A row new to
# both fails here until it has a value below (several words: the option's
# value, then partners it needs). The cells' tables are compared too.
declare -A optval=([--input-format]=xyz [--search]=kd [--leaf]=7
  [--voronoi]="$work/o.cells" [--density]="$work/o.dens"
  [--voronoi-format]="%i;%v;%n;%f --voronoi $work/o.cells"
  [--box]="-1,-1,-1,2,2,2 --density $work/o.dens"
  [--periodic]="xyz --box -0.01,-0.01,-0.01,1.01,1.01,1.01")
# "-x VALUE" and "--name VALUE" of each option line of a --help
help_opts() {
  sed -nE 's/^  (-(.), |    )--([a-z-]+)( ([^ ]+))?.*/-\2 \5\n--\3 \5/p' | grep -v '^- \|^-$' |
    sed 's/ *$//' | sort -u
}
"$frontdt" --help | help_opts >"$work/opts.f"
mpi 1 60 "$fmpi" --help | help_opts >"$work/opts.m"
comm -12 "$work/opts.f" "$work/opts.m" >"$work/opts.both"
[[ $(wc -l <"$work/opts.both") -ge 12 ]] ||
  fail "options of both: only $(tr '\n' ' ' <"$work/opts.both")"
# (fd 3: mpirun reads standard input)
while read -r opt value <&3; do
  checks=$((checks + 1))
  case $opt in
  -h | --help | -V | --version)
    "$frontdt" "$opt" >"$work/o.f" || fail "frontdt $opt: exit $?"
    mpi 2 60 "$fmpi" "$opt" >"$work/o.m" || fail "frontdt-mpi $opt: exit $?"
    [[ -s $work/o.f && -s $work/o.m ]] || fail "$opt: printed nothing"
    continue ;;
  esac
  af=("$opt") am=("$opt")
  if [[ $opt == -o || $opt == --output ]]; then
    af+=("$work/o.f.tets") am+=("$work/o.m.tets")
  elif [[ $opt == --dual ]]; then # it needs a polyMesh output
    rm -rf "$work/odf" "$work/odm"
    mkdir -p "$work/odf" "$work/odm"
    af+=(-o "$work/odf/polyMesh") am+=(-o "$work/odm/polyMesh")
  elif [[ -n $value ]]; then
    [[ -n ${optval[$opt]:-} ]] || { fail "$opt $value: no value to test it with"; continue; }
    read -ra words <<<"${optval[$opt]}"
    af+=("${words[@]}") am+=("${words[@]}")
  fi
  rm -f "$work/o.cells" "$work/o.dens"
  "$frontdt" -q --set-hash "${af[@]}" "$work/clusters.xyz" >"$work/o.f" 2>"$work/o.fe" ||
    { fail "frontdt ${af[*]}: exit $?"; sed 's/^/    /' "$work/o.fe" | head -5; continue; }
  for t in cells dens; do [[ -e $work/o.$t ]] && mv "$work/o.$t" "$work/o.$t.f"; done
  mpi 2 120 "$fmpi" -q --set-hash "${am[@]}" "$work/clusters.xyz" >"$work/o.m" 2>"$work/o.me" ||
    { fail "frontdt-mpi ${am[*]}: exit $?"; sed 's/^/    /' "$work/o.me" | head -5; continue; }
  hf=$(grep -E '^(set-)?hash: ' "$work/o.f" | sort) hm=$(grep -E '^(set-)?hash: ' "$work/o.m" | sort)
  [[ -n $hf && $hf == "$hm" ]] || fail "$opt: frontdt printed '$hf', frontdt-mpi '$hm'"
  if [[ $opt == -o || $opt == --output ]]; then
    cmp -s "$work/o.f.tets" "$work/o.m.tets" || fail "$opt: the two programs' files differ"
    rm -f "$work/o.f.tets" "$work/o.m.tets"
  fi
  if [[ $opt == --dual ]]; then
    diff -r "$work/odf" "$work/odm" >/dev/null || fail "$opt: the two programs' files differ"
  fi
  for t in cells dens; do
    if [[ -e $work/o.$t.f ]]; then
      cmp -s "$work/o.$t.f" "$work/o.$t" || fail "$opt: the two programs' o.$t differ"
    fi
    rm -f "$work/o.$t.f" "$work/o.$t"
  done
done 3<"$work/opts.both"
# frontdt-mpi has no man page: each long option of its --help is in
# doc/reference.md's section on it (frontdt's are in doc/frontdt.1, the
# docs test)
awk '/^### Distributed runs/ {t = 1; next} /^### / {t = 0} t' \
  "$(dirname "$0")/../doc/reference.md" >"$work/mpi.md"
checks=$((checks + 1))
for opt in $(awk '$1 ~ /^--/ {print $1}' "$work/opts.m"); do
  grep -qE -- "(^|[^a-z-])$opt([^a-z-]|$)" "$work/mpi.md" ||
    fail "doc/reference.md (Distributed runs) does not mention frontdt-mpi's $opt"
done
# A cone (rings of cocircular points, empty spheres as wide as the part):
# the ranks' probes vote for the replica mesh (src/mpi/mpi_run.c), every rank
# reads its apexes from its own copy, and no rank asks another (before it,
# 20,000 such points took 20 s on 2 ranks against serial's 0.3 s). The
# same mesh as serial's; --search kd keeps the queries. One rank too: its
# own probe (before, one rank ran the kd search alone, exhaustive on a
# sphere: 14,374 points of gen_points sphere over 2 minutes, 1.4 s now).
"$gen" cone 3000 19 "$work/cone.xyz" >/dev/null || fail "gen_points cone"
check cone "$work/cone.xyz" 1 2 3
for np in 1 2 3; do
  checks=$((checks + 1))
  mpi "$np" 300 "$fmpi" -q --stats "$work/cone.xyz" >/dev/null 2>"$work/cone.err" ||
    { fail "cone, $np ranks: exit $?"; continue; }
  grep -q '^  replica mesh ' "$work/cone.err" || fail "cone, $np ranks: no replica mesh"
  q=$(awk '$1 == "NODESEND" && $3 == "/" {print $2}' "$work/cone.err")
  [[ $q == 0 ]] || fail "cone, $np ranks: $q NODESENDs with the replica"
done
extra=(--search kd)
check "cone --search kd" "$work/cone.xyz" 2
extra=()
checks=$((checks + 1))
if mpi 2 300 "$fmpi" -q --stats --search kd "$work/cone.xyz" >/dev/null 2>"$work/cone.err"; then
  q=$(awk '$1 == "NODESEND" && $3 == "/" {print $2}' "$work/cone.err")
  [[ $q -gt 0 ]] || fail "cone --search kd, 2 ranks: no NODESEND (q='$q')"
  ! grep -q '^  replica mesh ' "$work/cone.err" || fail "cone --search kd: a replica mesh"
else
  fail "cone --search kd, 2 ranks: exit $?"
fi
# The Voronoi cells (issue 32, src/mpi/mpi_cells.c): frontdt-mpi's tables
# equal frontdt's byte for byte: the default format and the densities at
# every rank count; CSV, and every code with --box, at 3 ranks; with -o
# pieces beside them. On a lattice (cospherical), clusters, duplicates, a
# sphere's shell (every point on the hull) and uniform points. Errors give
# frontdt's message and exit code and leave no table: a point outside
# --box, two points too close for the cells, .vtu polyhedra (frontdt's
# alone).
# "x0,y0,z0,x1,y1,z1": FILE's bounding box grown by half its size
grown_box() {
  awk 'NF >= 3 && $1 !~ /^#/ { for (k = 1; k <= 3; k++) { if (!(k in lo) || $k < lo[k]) lo[k] = $k
         if (!(k in hi) || $k > hi[k]) hi[k] = $k } }
       END { for (k = 1; k <= 3; k++) { d = (hi[k] - lo[k]) / 2; a[k] = lo[k] - d; b[k] = hi[k] + d }
             printf "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", a[1], a[2], a[3], b[1], b[2], b[3] }' "$1"
}
# cells_same NAME NP FILE OPTIONS...: frontdt's and frontdt-mpi's tables
# (the options name $work/c.t and $work/c.d)
cells_same() {
  local name=$1 np=$2 f=$3
  shift 3
  checks=$((checks + 1))
  rm -f "$work"/c.t "$work"/c.d "$work"/c.t.f "$work"/c.d.f
  "$frontdt" -q "$f" "$@" 2>"$work/c.err" ||
    { fail "$name: frontdt exit $?"; head -3 "$work/c.err"; return; }
  for x in t d; do [[ -e $work/c.$x ]] && mv "$work/c.$x" "$work/c.$x.f"; done
  mpi "$np" 300 "$fmpi" -q "$f" "$@" 2>"$work/c.err" ||
    { fail "$name, $np ranks: exit $?"; head -3 "$work/c.err"; return; }
  for x in t d; do
    [[ -e $work/c.$x.f ]] || continue
    cmp -s "$work/c.$x.f" "$work/c.$x" || fail "$name, $np ranks: the table $x differs from frontdt's"
  done
}
# (every rank count on two families, two ranks on the others: the suite
# runs three times in CI)
allcodes='%i %x %y %z %q %v %F %s %n %f %c %C %d %h %%'
for fam in lattice dup clusters sphere uniform; do
  f=$work/$fam.xyz
  [[ -e $f ]] || "$gen" "$fam" 3000 19 "$f" >/dev/null || { fail "gen_points $fam"; continue; }
  cnps=(2)
  [[ $fam == lattice || $fam == dup ]] && cnps=("${nps[@]}")
  for np in "${cnps[@]}"; do
    cells_same "cells of $fam" "$np" "$f" --voronoi "$work/c.t" --density "$work/c.d"
  done
  cells_same "CSV cells of $fam" 3 "$f" --voronoi "$work/c.t" --voronoi-format "$allcodes" \
    --box "$(grown_box "$f")"
  [[ $fam == lattice || $fam == sphere ]] || continue
  mpi 3 300 "$fmpi" -q "$f" --voronoi "$work/c.csv" -o "$work/cp.pfdtb" 2>"$work/c.err" ||
    fail "cells of $fam beside pieces: exit $?"
  "$frontdt" -q "$f" --voronoi "$work/c.f.csv" && cmp -s "$work/c.f.csv" "$work/c.csv" ||
    fail "CSV cells of $fam beside pieces: differ from frontdt's"
  rm -f "$work"/cp*.fdtb "$work/cp.pfdtb" "$work/c.csv" "$work/c.f.csv"
done
# a shuffled input: each point's cell the same bits, its row moved with it
checks=$((checks + 1))
awk 'BEGIN {srand(5)} {print rand() "\t" $0}' "$work/uniform.xyz" | sort -k1,1 | cut -f2- \
  >"$work/shuffled.xyz"
rowfmt='%x %y %z %v %F %s %c %d %h'
"$frontdt" -q "$work/uniform.xyz" --voronoi "$work/c.f.txt" --voronoi-format "$rowfmt" &&
  mpi 3 300 "$fmpi" -q "$work/shuffled.xyz" --voronoi "$work/c.txt" --voronoi-format "$rowfmt" ||
  fail "cells of a shuffled input: exit $?"
cmp -s "$work/uniform.xyz" "$work/shuffled.xyz" && fail "the shuffle did not shuffle"
cmp -s <(sort "$work/c.f.txt") <(sort "$work/c.txt") ||
  fail "cells of a shuffled input under MPI: other values than frontdt's on the input"
# fewer input points than ranks (empty blocks), a duplicate among them
printf '0 0 0\n1 0 0\n0 1 0\n0 0 1\n0.3 0.3 0.3\n1 0 0\n' >"$work/tiny.xyz"
cells_same "cells of 6 points" 7 "$work/tiny.xyz" --voronoi "$work/c.t" --density "$work/c.d"
# errors: frontdt's message and code, no table
cells_error() {
  local name=$1 f=$2
  shift 2
  checks=$((checks + 1))
  rm -f "$work/c.t"
  "$frontdt" -q "$f" --voronoi "$work/c.t" "$@" 2>"$work/c.ferr"
  local want=$?
  mpi 3 300 "$fmpi" -q "$f" --voronoi "$work/c.t" "$@" 2>"$work/c.err"
  local got=$?
  [[ $want -ne 0 && $got == "$want" ]] || fail "$name: frontdt-mpi exit $got, frontdt $want"
  local mf mm
  mf=$(grep -m1 '^frontdt:' "$work/c.ferr" | sed 's/^frontdt: //')
  mm=$(grep -m1 '^frontdt-mpi:' "$work/c.err" | sed 's/^frontdt-mpi: //')
  [[ -n $mf && $mf == "$mm" ]] || fail "$name: frontdt-mpi said '$mm', frontdt '$mf'"
  [[ ! -e $work/c.t ]] || fail "$name: a table was left"
}
cells_error "a point outside --box" "$work/lattice.xyz" --box 0,0,0,1,1,1
awk '{print} NR == 101 {printf "%.17g %.17g %.17g\n", $1, $2 + 2e-16, $3}' \
  "$work/uniform.xyz" >"$work/close.xyz"
cells_error "two points too close for the cells" "$work/close.xyz"
# --voronoi FILE.vtu: the polyhedra made on rank 0 from the gathered mesh,
# frontdt's bytes (beside the ranks' --density table); refused beside pieces
"$frontdt" -q "$work/uniform.xyz" --voronoi "$work/c.f.vtu" --density "$work/c.f.d" ||
  fail "frontdt --voronoi FILE.vtu"
for np in 1 3; do
  checks=$((checks + 1))
  rm -f "$work/c.vtu" "$work/c.d"
  mpi "$np" 300 "$fmpi" -q "$work/uniform.xyz" --voronoi "$work/c.vtu" --density "$work/c.d" ||
    fail "--voronoi FILE.vtu on $np ranks: exit $?"
  cmp -s "$work/c.f.vtu" "$work/c.vtu" && cmp -s "$work/c.f.d" "$work/c.d" ||
    fail "--voronoi FILE.vtu on $np ranks: not frontdt's files"
done
checks=$((checks + 1))
rm -f "$work/c.vtu"
mpi 2 60 "$fmpi" -q "$work/uniform.xyz" --voronoi "$work/c.vtu" -o "$work/cv.pvtu" 2>"$work/c.err"
[[ $? -eq 1 ]] && grep -q "not beside an -o of pieces" "$work/c.err" && [[ ! -e $work/c.vtu ]] ||
  fail "--voronoi FILE.vtu beside pieces under MPI: not refused as a usage error"
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

# The distributed setup (§3.1, src/mpi/mpi_setup.c): each rank parses its byte
# slice of a text file, cut at line starts wherever the byte offsets fall
# (mid-line, as a rule). A header line, comments, blank lines, CRLF and
# commas, on every rank count; duplicates spread across slices (the file
# twice over, so each point's duplicate is in another rank's slice), whose
# gathered .tets must be serial's byte for byte (the first input id of
# each class survives, as src/geom/prepare.c's merge); the whole-read fallback
# for other formats (PLY) and standard input (read by rank 0, scattered).
{
  printf '\xef\xbb\xbfX,Y,Z\r\n# clusters, as csv\r\n\r\n'
  awk '{printf "%s,%s,%s%s\r\n", $1, $2, $3, (NR % 97 == 0 ? "  # a comment" : "")}
       NR % 211 == 0 {printf "\r\n# between\r\n"}' "$work/clusters.xyz"
} >"$work/header.csv"
check "header csv" "$work/header.csv" "${nps[@]}"
cat "$work/clusters.xyz" "$work/clusters.xyz" >"$work/twice.xyz"
check "duplicates across slices" "$work/twice.xyz" 2 3 7
# every lattice point five times: the class at a cut is five equal points,
# which must all go to one side (split, two ranks would each build on
# the point, and the run fails)
for i in 1 2 3 4 5; do cat "$work/lattice.xyz"; done >"$work/lattice5.xyz"
check "lattice, each point five times" "$work/lattice5.xyz" 2 3 7
"$frontdt" --mode serial -q -o "$work/twice_ref.tets" "$work/twice.xyz" || fail "serial -o twice"
checks=$((checks + 1))
mpi 3 120 "$fmpi" -q -o "$work/twice3.tets" "$work/twice.xyz" || fail "-o twice, 3 ranks"
cmp -s "$work/twice_ref.tets" "$work/twice3.tets" || fail "-o twice, 3 ranks: differs from serial"
checks=$((checks + 1))
mpi 3 60 "$fmpi" -q --stats "$work/twice.xyz" 2>"$work/st" >/dev/null
grep -q "each rank read its slice of the file; 6000 points, 3000 duplicates merged" "$work/st" ||
  { fail "twice, 3 ranks: --stats does not say slices and 3000 duplicates"; cat "$work/st"; }
"$gen" uniform 3000 23 "$work/u.ply" >/dev/null || fail "gen_points ply"
check "ply (whole-read fallback)" "$work/u.ply" 3
checks=$((checks + 1))
mpi 2 60 "$fmpi" -q --stats "$work/u.ply" 2>"$work/st" >/dev/null
grep -q "each rank read its vertices of the binary PLY" "$work/st" ||
  fail "ply: --stats does not say vertex slices"
# PLY layouts (written by python3; skipped without it): big-endian floats
# with a colour, after a fixed-size element (sliced by vertex); a face
# list after the vertices (read whole); ASCII (read whole); a NaN in the
# last vertex (every rank exits 2 with frontdt's message).
if "$python" - "$work" "$work/clusters.xyz" <<'PY'
import struct, sys
work, src = sys.argv[1], sys.argv[2]
pts = [tuple(float(v) for v in l.split()[:3]) for l in open(src) if l.strip()]
def ply(name, fmt, props, rows, pre=b"", post=b"", tail=b""):
    with open(f"{work}/{name}.ply", "wb") as f:
        f.write(b"ply\nformat " + fmt + b" 1.0\n" + pre + b"element vertex %d\n" % len(rows)
                + props + post + b"end_header\n")
        for r in rows:
            f.write(r)
        f.write(tail)
be = [struct.pack(">fffB", x, y, z, 7) for x, y, z in pts]
ply("be", b"binary_big_endian",
    b"property float x\nproperty float y\nproperty float z\nproperty uchar red\n", be,
    pre=b"element camera 2\nproperty double fov\nproperty int id\n"
    + b"", tail=b"")
# the camera element's 2 x 12 bytes precede the vertices
data = open(f"{work}/be.ply", "rb").read()
head, body = data.split(b"end_header\n", 1)
open(f"{work}/be.ply", "wb").write(head + b"end_header\n" + struct.pack(">di", 1.0, 1) * 2 + body)
le = [struct.pack("<ddd", x, y, z) for x, y, z in pts]
ply("faces", b"binary_little_endian",
    b"property double x\nproperty double y\nproperty double z\n", le,
    post=b"element face 1\nproperty list uchar int vertex_indices\n",
    tail=struct.pack("<Biii", 3, 0, 1, 2))
ply("ascii", b"ascii", b"property double x\nproperty double y\nproperty double z\n",
    [b"%r %r %r\n" % p for p in pts])
nan = le[:-1] + [struct.pack("<ddd", 0.5, float("nan"), 0.5)]
ply("nan", b"binary_little_endian",
    b"property double x\nproperty double y\nproperty double z\n", nan)
PY
then
  check "ply big-endian floats after a camera element" "$work/be.ply" 2 3
  check "ply with a face list" "$work/faces.ply" 3
  check "ply ascii" "$work/ascii.ply" 2
  checks=$((checks + 1))
  mpi 3 60 "$fmpi" -q --stats "$work/be.ply" 2>"$work/st" >/dev/null
  grep -q "each rank read its vertices of the binary PLY" "$work/st" || fail "be.ply: not sliced"
  mpi 3 60 "$fmpi" -q --stats "$work/faces.ply" 2>"$work/st" >/dev/null
  grep -q "every rank read the whole input" "$work/st" || fail "faces.ply: not read whole"
else
  echo "skip: PLY layouts ($python absent)"
fi
if [[ ${#oversub[@]} -gt 0 ]]; then
  checks=$((checks + 1))
  ref=$("$frontdt" --mode serial -q --set-hash "$work/clusters.xyz")
  # Open MPI 4's mpirun itself now and then crashes forwarding standard
  # input (orte_iof_hnp_read_local_handler, open-mpi/ompi#7483): a crash
  # of the launcher, named in its message, is tried again (3 times)
  for try in 1 2 3; do
    got=$(mpi 3 60 "$fmpi" -q --set-hash --input-format xyz - <"$work/clusters.xyz" 2>"$work/stdin.err")
    grep -q "orte_iof_hnp_read_local_handler" "$work/stdin.err" || break
    echo "note: mpirun crashed forwarding standard input (try $try)"
  done
  [[ -n $ref && $got == "$ref" ]] || { fail "standard input, 3 ranks: '$got', serial '$ref'"; cat "$work/stdin.err"; }
else
  # MPICH's launcher (hydra 4.0) aborts forwarding this 180 kB to any
  # program ("process reading stdin too slowly; can't keep up"), wc -c
  # included
  echo "skip: standard input (not Open MPI's launcher)"
fi

# Bad input in a slice: every rank exits 2 with the error of a whole read
# (the file's first bad line, its number counted over the slices before
# it), and nothing is written. Lines 2950 (the last rank's slice of 3)
# and then 1500 as well (rank 1's of 4, reported first).
rankvar='${OMPI_COMM_WORLD_RANK:-${PMI_RANK:-?}}'
awk 'NR == 2950 {print "1.0 2.0 oops"; next} {print}' "$work/clusters.xyz" >"$work/bad1.xyz"
awk 'NR == 2950 {print "1.0 2.0 oops"; next} NR == 1500 {print "1 2"; next} {print}' \
  "$work/clusters.xyz" >"$work/bad2.xyz"
printf '0 0 0\n1 0 0\n0 1 0\n1 1 0\n2 2 0\n0 0 0\n' >"$work/flat.xyz"
bads=("bad1.xyz 3" "bad2.xyz 4" "flat.xyz 3")
[[ -s $work/nan.ply ]] && bads+=("nan.ply 3")
for spec in "${bads[@]}"; do
  set -- $spec
  checks=$((checks + 1))
  want=$("$frontdt" --mode serial -q "$work/$1" 2>&1 | sed 's/^frontdt: //')
  rm -f "$work/bad.tets"
  out=$(mpi "$2" 60 bash -c "\"\$0\" -q -o \"$work/bad.tets\" \"$work/$1\"; echo \"rank-exit $rankvar \$?\"" "$fmpi" 2>"$work/ferr")
  n2=$(grep -c '^rank-exit [0-9?]* 2$' <<<"$out")
  [[ $n2 -eq $2 ]] || { fail "$1 on $2 ranks: $n2 of $2 ranks ended with exit 2"; echo "$out"; }
  got=$(grep '^frontdt-mpi: ' "$work/ferr" | sed 's/^frontdt-mpi: //')
  case $1 in
    flat.xyz) [[ $got == *"flat.xyz: all 5 distinct points are coplanar"* ]] ||
            fail "flat on $2 ranks: '$got'" ;;
    *) [[ -n $want && $got == "$want" ]] || fail "$1 on $2 ranks: '$got', serial says '$want'" ;;
  esac
  ls -A "$work" | grep -q 'bad\.tets' && fail "$1 on $2 ranks: output left behind"
done

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

# -o BASE.pfdtb and -o BASE.pele: one piece a rank and a text index, no
# gather. All pieces together hold the serial run's tets and hull faces,
# each the same way round (stream_readback.py --pieces: the .pfdtb through
# doc/reference.md's read_pieces when numpy is there; the headers, the index's
# names and counts), and the .node that every rank wrote its lines of is
# the serial run's byte for byte. Inputs: 1-7 ranks on clusters,
# duplicates spread across slices, five points on 7 ranks (ranks with no
# tets: empty pieces).
readback=$(dirname "$0")/stream_readback.py
readme=$(dirname "$0")/../doc/reference.md
pieces_check() {
  local name=$1 f=$2 np=$3 ext=$4 d="$work/pc"
  checks=$((checks + 1))
  rm -rf "$d"
  mkdir "$d"
  "$frontdt" --mode serial -q -o "$d/ref.ele" "$f" || { fail "$name: serial .ele"; return; }
  if ! mpi "$np" 120 "$fmpi" -q -o "$d/m.$ext" "$f" 2>"$d/err"; then
    fail "$name, -o .$ext, $np ranks: exit $?"; sed 's/^/    /' "$d/err" | tail -5; return
  fi
  if ! "$python" "$readback" "$frontdt" "$readme" --pieces "$d/m.$ext" "$d/ref" >"$d/log" 2>&1; then
    fail "$name, -o .$ext, $np ranks: the pieces are not the serial mesh"
    sed 's/^/    /' "$d/log" | tail -5
  fi
  local want=$((np + 5)) # the pieces, the index, ref.{node,ele,face,neigh}
  [[ $ext == pele ]] && want=$((2 * np + 6)) # .face pieces and the .node
  [[ $(ls -A "$d" | grep -vcE '^(err|log)$') -eq $want ]] ||
    fail "$name, -o .$ext, $np ranks: files $(ls -A "$d" | tr '\n' ' ')"
}
for np in "${nps[@]}"; do
  pieces_check clusters "$work/clusters.xyz" "$np" pfdtb
  pieces_check clusters "$work/clusters.xyz" "$np" pele
done
for np in 3 7; do
  pieces_check "duplicates across slices" "$work/twice.xyz" "$np" pfdtb
  pieces_check "duplicates across slices" "$work/twice.xyz" "$np" pele
done
pieces_check "five points" "$work/five.xyz" 7 pele
pieces_check "five points" "$work/five.xyz" 7 pfdtb
grep -q '^piece m_6.fdtb 0 0$' "$work/pc/m.pfdtb" ||
  fail "five points on 7 ranks: rank 6 holds tets (the check of an empty piece checks nothing)"
# A rank whose piece fails once written (hidden --inject-write-failure):
# every rank exits 5 and no piece, .node or index is left (the pieces
# already renamed are removed again); a missing directory: exit 5 too.
for spec in "3 pfdtb 1" "3 pele 2" "4 pele 0" "2 pvtu 1"; do
  set -- $spec
  checks=$((checks + 1))
  rm -rf "$work/wf"
  mkdir "$work/wf"
  mpi "$1" 60 "$fmpi" -q --inject-write-failure "$3" -o "$work/wf/m.$2" "$work/clusters.xyz" \
    2>"$work/wferr"
  rc=$?
  [[ $rc -eq 5 ]] || fail "write failure on rank $3 of $1, .$2: exit $rc"
  grep -q "rank $3: .*injected failure" "$work/wferr" || fail "write failure, .$2: no message"
  [[ -z $(ls -A "$work/wf") ]] || fail "write failure on rank $3 of $1, .$2: left $(ls -A "$work/wf" | tr '\n' ' ')"
done
for ext in pfdtb pele; do
  checks=$((checks + 1))
  mpi 3 60 "$fmpi" -q -o "$work/none/m.$ext" "$work/clusters.xyz" 2>/dev/null
  rc=$?
  [[ $rc -eq 5 && ! -e $work/none ]] || fail ".$ext into a missing directory: exit $rc"
done

# An output file of the set that is the input (here the .node): exit 1,
# nothing written, the input as it was.
checks=$((checks + 1))
mkdir -p "$work/in"
"$frontdt" --mode serial -q -o "$work/in/m.ele" "$work/clusters.xyz" || fail "serial .ele"
cp "$work/in/m.node" "$work/in/orig.node"
mpi 2 60 "$fmpi" -q -o "$work/in/m.pele" "$work/in/m.node" 2>/dev/null
rc=$?
[[ $rc -eq 1 && ! -e $work/in/m.pele && ! -e $work/in/m_0.ele ]] &&
  cmp -s "$work/in/m.node" "$work/in/orig.node" || fail ".pele whose .node is the input: exit $rc"

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

# SIGINT to mpirun (Open MPI forwards it to every rank): every rank ends
# (exit 6, "interrupted"), and -o BASE.pvtu / .pfdtb / .pele leaves either
# nothing or the complete set (the index, every piece, the .node), never a
# piece or an index alone; signals at a few moments, at least one of them
# mid-run.
if [[ ${#oversub[@]} -gt 0 ]]; then
  "$gen" uniform 100000 31 "$work/u100k.xyz" >/dev/null || fail "gen_points 100k"
  interrupted=0
  complete_pvtu="mesh.pvtu mesh_0.vtu mesh_1.vtu mesh_2.vtu "
  complete_pfdtb="mesh.pfdtb mesh_0.fdtb mesh_1.fdtb mesh_2.fdtb "
  complete_pele="mesh.node mesh.pele mesh_0.ele mesh_0.face mesh_1.ele mesh_1.face mesh_2.ele mesh_2.face "
  for spec in "0.6 pvtu" "1.2 pvtu" "2.4 pvtu" "1.5 pfdtb" "2.0 pele"; do
    set -- $spec
    delay=$1 ext=$2
    checks=$((checks + 1))
    rm -rf "$work/sig"
    mkdir "$work/sig"
    "$mpirun" "${oversub[@]}" -np 3 "$fmpi" -q -o "$work/sig/mesh.$ext" "$work/u100k.xyz" \
      2>"$work/sigerr" &
    pid=$!
    sleep "$delay"
    kill -INT "$pid" 2>/dev/null
    for _ in $(seq 60); do kill -0 "$pid" 2>/dev/null || break; sleep 1; done
    if kill -0 "$pid" 2>/dev/null; then
      fail "SIGINT after ${delay}s (.$ext): mpirun still runs 60 s later"
      kill -KILL "$pid"
    fi
    wait "$pid" 2>/dev/null
    grep -q "frontdt-mpi: interrupted" "$work/sigerr" && interrupted=$((interrupted + 1))
    left=$(ls -A "$work/sig" | LC_ALL=C sort | tr '\n' ' ')
    complete=complete_$ext
    [[ -z $left || $left == "${!complete}" ]] ||
      fail "SIGINT after ${delay}s (.$ext): left '$left'"
  done
  [[ $interrupted -gt 0 ]] || fail "SIGINT: no run was interrupted"
else
  echo "skip: SIGINT (not Open MPI's launcher)"
fi

# Periodic domains (issue 33): every rank reads the input and builds its
# share of the box's slabs; the rows gathered to rank 0 are frontdt's .tets
# byte for byte, with its --hash and --set-hash, and the cells' and
# densities' tables (each rank its slabs' cells) frontdt's, at 1-4 ranks,
# periodic on three axes (with a duplicate point: its row once) and on two
# (x and z, walls of points across y); TetGen's set and an OpenFOAM
# polyMesh on 2 ranks are frontdt's; a point outside the box gives
# frontdt's message and code and no file.
"$gen" uniform 3000 41 "$work/pu.xyz" >/dev/null
awk '{ print $1, 0.02 + 0.96 * $2, $3 }
     END { for (i = 0; i < 20; i++) for (j = 0; j < 20; j++)
             print (i + 0.5) / 20, 0.001, (j + 0.5) / 20 "\n" (i + 0.5) / 20, 0.999, (j + 0.5) / 20 }' \
  "$work/pu.xyz" >"$work/pch.xyz"
sed -n 7p "$work/pu.xyz" >>"$work/pu.xyz"
for spec in "pu xyz" "pch x,z"; do
  set -- $spec
  ref=$("$frontdt" "$work/$1.xyz" --periodic "$2" --box 0,0,0,1,1,1 -o "$work/$1.ref.tets" \
    --hash --set-hash -q --voronoi "$work/$1.ref.cells" --voronoi-format '%i %v %F %n %f %c %h' \
    --density "$work/$1.ref.dens" | sort)
  [[ -n $ref && -s $work/$1.ref.cells ]] || fail "periodic $1: frontdt gave no hashes or cells"
  for np in 1 2 3 4; do
    checks=$((checks + 1))
    got=$(mpi "$np" 300 "$fmpi" "$work/$1.xyz" --periodic "$2" --box 0,0,0,1,1,1 \
      -o "$work/$1.$np.tets" --hash --set-hash -q --voronoi "$work/$1.$np.cells" \
      --voronoi-format '%i %v %F %n %f %c %h' --density "$work/$1.$np.dens" | sort)
    [[ $got == "$ref" ]] && cmp -s "$work/$1.ref.tets" "$work/$1.$np.tets" &&
      cmp -s "$work/$1.ref.cells" "$work/$1.$np.cells" &&
      cmp -s "$work/$1.ref.dens" "$work/$1.$np.dens" ||
      fail "periodic $1 on $np ranks: '$got', frontdt '$ref' (or the tables differ)"
  done
done
# pieces of a periodic run (no row gathered): each rank's sorted rows as a
# .pfdtb piece (flags 8 | 4 | 16) or a laid-out .vtu piece (the points and
# images its tets use, each one's input id), the index's set hash frontdt's; every row of
# frontdt's .tets once over the pieces (stream_readback.py
# --periodic-pieces; the .pvtu through VTK where python3 has it). .pele
# and --hash with pieces refused.
for spec in "pu xyz" "pch x,z"; do
  set -- $spec
  "$frontdt" "$work/$1.xyz" --periodic "$2" --box 0,0,0,1,1,1 -q --set-hash \
    >"$work/$1.ref.sh"
  for np in 1 2 3; do
    for ext in pfdtb pvtu; do
      checks=$((checks + 1))
      rm -rf "$work/pp" && mkdir -p "$work/pp"
      got=$(mpi "$np" 300 "$fmpi" "$work/$1.xyz" --periodic "$2" --box 0,0,0,1,1,1 -q \
        --set-hash -o "$work/pp/m.$ext") || { fail "periodic $1 on $np ranks: -o .$ext"; continue; }
      [[ $got == "$(cat "$work/$1.ref.sh")" ]] ||
        fail "periodic $1 on $np ranks, .$ext: '$got', frontdt '$(cat "$work/$1.ref.sh")'"
      "$python" "$readback" "$frontdt" "$readme" --periodic-pieces "$work/pp/m.$ext" \
        "$work/$1.xyz" "$work/$1.ref.tets" 0,0,0,1,1,1 "$2" <"$work/$1.ref.sh" >/dev/null ||
        fail "periodic $1 on $np ranks: the .$ext pieces are not frontdt's rows"
    done
  done
done
for bad in "-o $work/pp/x.pele" "--hash -o $work/pp/x.pvtu"; do
  checks=$((checks + 1))
  mpi 2 60 "$fmpi" "$work/pu.xyz" --periodic xyz --box 0,0,0,1,1,1 -q $bad 2>/dev/null
  rc=$?
  [[ $rc -eq 1 && ! -e $work/pp/x.pele && ! -e $work/pp/x.pvtu ]] ||
    fail "periodic with $bad: exit $rc"
done
# the laid-out formats on rank 0 (TetGen's set with its periodic .neigh, an
# OpenFOAM polyMesh with cyclic patches): frontdt's files byte for byte
mkdir -p "$work/pf1" "$work/pf2"
"$frontdt" "$work/pch.xyz" --periodic x,z --box 0,0,0,1,1,1 -q -o "$work/pf1/m.ele" \
  -o "$work/pf1/polyMesh" || fail "periodic x,z: frontdt -o .ele -o polyMesh"
for out in m.ele polyMesh; do
  checks=$((checks + 1))
  mpi 2 300 "$fmpi" "$work/pch.xyz" --periodic x,z --box 0,0,0,1,1,1 -q -o "$work/pf2/$out" ||
    fail "periodic x,z on 2 ranks: -o $out"
done
for f in m.node m.ele m.face m.neigh polyMesh/points polyMesh/faces polyMesh/owner \
  polyMesh/neighbour polyMesh/boundary; do
  cmp -s "$work/pf1/$f" "$work/pf2/$f" || fail "periodic x,z on 2 ranks: $f differs"
done
# --dual (the Voronoi cells as a polyMesh, written on rank 0 from the
# gathered mesh): frontdt's files byte for byte, plain and periodic, at 1-3
# ranks; without a gathered polyMesh output it is a usage error
mkdir -p "$work/pd0" "$work/pdp0"
"$frontdt" "$work/uniform.xyz" -q -o "$work/pd0/polyMesh" --dual 2>"$work/pd.err" ||
  fail "frontdt --dual: $(cat "$work/pd.err")"
"$frontdt" "$work/pch.xyz" --periodic x,z --box 0,0,0,1,1,1 -q -o "$work/pdp0/polyMesh" --dual \
  2>"$work/pd.err" || fail "frontdt --periodic --dual: $(cat "$work/pd.err")"
for np in 1 2 3; do
  checks=$((checks + 1))
  rm -rf "$work/pd$np" "$work/pdp$np"
  mkdir -p "$work/pd$np" "$work/pdp$np"
  mpi "$np" 300 "$fmpi" "$work/uniform.xyz" -q -o "$work/pd$np/polyMesh" --dual ||
    fail "--dual on $np ranks"
  mpi "$np" 300 "$fmpi" "$work/pch.xyz" --periodic x,z --box 0,0,0,1,1,1 -q \
    -o "$work/pdp$np/polyMesh" --dual || fail "--periodic --dual on $np ranks"
  for f in points faces owner neighbour boundary; do
    cmp -s "$work/pd0/polyMesh/$f" "$work/pd$np/polyMesh/$f" ||
      fail "--dual on $np ranks: $f differs from frontdt's"
    cmp -s "$work/pdp0/polyMesh/$f" "$work/pdp$np/polyMesh/$f" ||
      fail "--periodic --dual on $np ranks: $f differs from frontdt's"
  done
done
checks=$((checks + 1))
"$frontdt" "$work/pch.xyz" --periodic x,z --box 0,0,0,1,1,1 -q --voronoi "$work/pv0.vtu" ||
  fail "frontdt --periodic --voronoi FILE.vtu"
mpi 2 300 "$fmpi" "$work/pch.xyz" --periodic x,z --box 0,0,0,1,1,1 -q --voronoi "$work/pv2.vtu" &&
  cmp -s "$work/pv0.vtu" "$work/pv2.vtu" ||
  fail "--periodic --voronoi FILE.vtu on 2 ranks: not frontdt's file"
for bad in "" "-o $work/pdx.vtu" "-o $work/pdx.pvtu"; do
  checks=$((checks + 1))
  # shellcheck disable=SC2086 # $bad is the options, split on purpose
  mpi 2 60 "$fmpi" "$work/uniform.xyz" -q --dual $bad 2>"$work/pd.err"
  rc=$?
  [[ $rc -eq 1 ]] && grep -q "needs an -o CASE/constant/polyMesh" "$work/pd.err" &&
    [[ ! -e $work/pdx.vtu && ! -e $work/pdx.pvtu ]] || fail "--dual $bad under MPI: exit $rc"
done
checks=$((checks + 1))
printf '0.5 1.5 0.5\n' >>"$work/pu.xyz"
want=$("$frontdt" "$work/pu.xyz" --periodic xyz --box 0,0,0,1,1,1 -q 2>&1)
wcode=$?
mpi 3 300 "$fmpi" "$work/pu.xyz" --periodic xyz --box 0,0,0,1,1,1 -o "$work/pbad.tets" \
  2>"$work/pbad.err"
gcode=$?
got=$(head -1 "$work/pbad.err") # then mpirun's own lines
[[ $gcode -eq $wcode && $wcode -ne 0 && ${got#frontdt-mpi: } == "${want#frontdt: }" &&
   ! -e $work/pbad.tets ]] ||
  fail "periodic, a point outside the box: exit $gcode '$got', frontdt $wcode '$want'"

echo "$checks checks, $fails failures"
[[ $fails -eq 0 ]]
