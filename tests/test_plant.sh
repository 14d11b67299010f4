#!/usr/bin/env bash
# The mesh certificate at run time (issue 31 item 6; src/mesh/certify.h).
# Usage: test_plant.sh FRONTDT GEN_POINTS PLANTED
# PLANTED=0 (every build): on a rotated lattice, a cylinder and a 12-digit
#   sphere, the serial run (the one-part engine: its mesh certified, then
#   emitted) and the serial streamed run (the parts in sweep order, each
#   part's mesh certified) give the kd front's set hash, exit 0, and --stats
#   says every tet came from a certified mesh.
# PLANTED=1 (a build with -Dplant=insphere, .ci/run's build-plant: the
#   insertion's insphere without its exact stage and perturbation): the same
#   runs stop with exit 3 and say the certificate failed, and print no hash;
#   threaded runs stop likewise, or give the right mesh where they built
#   none: never a wrong one.
set -u
frontdt=$1 gen=$2 planted=$3
work=$(mktemp -d "${TMPDIR:-/tmp}/fdt-test-plant.XXXXXX")
trap 'rm -rf "$work"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

# Without the planted bug the families may be smaller: FDT_TEST_SIZE_SCALE
# (a factor in (0, 1], as tests/testutil.h's test_size) halves them in the
# sanitizer and coverage runs (.ci/run), whose kd fronts at -O0 took 145 s;
# the planted build keeps the sizes its bug was caught at.
scale=1
[[ $planted == 0 && -n ${FDT_TEST_SIZE_SCALE:-} ]] && scale=$FDT_TEST_SIZE_SCALE
for fam in "rotlattice 8000" "cylinder 10000" "sphere12 10000"; do
  set -- $fam
  f="$work/$1.xyz"
  n=$(awk -v n="$2" -v s="$scale" 'BEGIN { m = (s > 0 && s <= 1) ? int(n * s) : n; print m < 100 ? 100 : m }')
  "$gen" "$1" "$n" 7 "$f" >/dev/null || { fail "gen_points $1"; continue; }
  ref=$("$frontdt" --mode serial --search kd -q --set-hash "$f" | sed -n 's/^set-hash: //p')
  [[ -n $ref ]] || { fail "$1: no set hash from the kd front"; continue; }
  for serial in "--mode serial" "--mode serial --stream"; do
  "$frontdt" $serial -q --set-hash --stats "$f" >"$work/out" 2>"$work/err"
  rc=$?
  got=$(sed -n 's/^set-hash: //p' "$work/out")
  if [[ $planted == 1 ]]; then
    [[ $rc == 3 ]] || fail "$1 [$serial] (planted bug): exit $rc, want 3 (set hash '$got', kd $ref)"
    grep -q "mesh certificate failed" "$work/err" || fail "$1 [$serial] (planted bug): no certificate message"
    [[ -z $got ]] || fail "$1 [$serial] (planted bug): a set hash was printed"
    echo "planted bug stopped on $1 [$serial]: $(grep -m1 'certificate' "$work/err")"
    [[ $serial == "--mode serial" ]] || continue
    # The threaded engine's meshes (the mesh of every point, a part's own
    # mesh) and the serial streamed front's: exit 3, or the right mesh where
    # a run built no mesh; never a wrong one.
    for opts in "-t 2" "-t 2 --search mesh" "-t 3 --mode message" "-t 2 --stream"; do
      "$frontdt" $opts -q --set-hash "$f" >"$work/out" 2>"$work/err"
      rc=$?
      got=$(sed -n 's/^set-hash: //p' "$work/out")
      if [[ $rc == 3 ]]; then
        grep -q "mesh certificate failed" "$work/err" || fail "$1 [$opts]: exit 3 without the message"
      elif [[ $rc != 0 || $got != "$ref" ]]; then
        fail "$1 [$opts] (planted bug): exit $rc, set hash '$got', kd $ref"
      fi
      echo "  [$opts]: exit $rc $(grep -m1 'certificate' "$work/err")"
    done
  else
    [[ $rc == 0 && $got == "$ref" ]] || fail "$1 [$serial]: exit $rc, set hash '$got', kd front $ref"
    tets=$(awk '$1 == "tets" {print $2}' "$work/err")
    fin=$(awk '/final from mesh/ {print $4}' "$work/err")
    [[ -n $tets && $tets == "$fin" ]] ||
      fail "$1 [$serial]: --stats says $fin of $tets tets came from a certified mesh"
  fi
  done
done
((fails == 0)) && echo "plant (planted=$planted): all passed"
((fails == 0))
