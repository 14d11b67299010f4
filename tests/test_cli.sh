#!/bin/bash
# End-to-end tests of the frontdt command-line tool (src/cli/main.c).
#
# usage: test_cli.sh FRONTDT BAD_DIR
#   FRONTDT  the built frontdt executable
#   BAD_DIR  tests/bad: hostile inputs and EXPECTED.txt, one row per file:
#            FILE EXIT_CODE MESSAGE-SUBSTRING (tab- or blank-separated;
#            the message is the rest of the line; '#' starts a comment)
#
# Covers: --help/--version, reading from a pipe and a FIFO, usage errors (exit 1), every hostile input
# (its exit code and message, and no output or temporary file left), an
# unknown output extension refused before any computation (exit 1),
# --format against the extension (exit 1), --no-clobber (exit 5), an
# output that would overwrite the input refused (exit 1, every output family
# against every way of naming the input, the input's bytes unchanged), an
# output directory that does not exist (exit 5, nothing left), write errors part-
# way (file size limit, in the middle of a TetGen set too, /dev/full: exit
# 5, nothing left), SIGTERM and SIGINT
# during a long run and during the write (exit 6, nothing left), several
# outputs all or none (SIGINT during the second; a failure or signal at
# every step of the final commit: all old or all new), --demo,
# repeatability (byte-identical .tets, identical --hash), independence of
# input order (shuffled copy mapped back), --check, --stats/--stats-json,
# duplicate reporting, --pin refused (said once), every output format;
# standard input ('-', pipes, FIFOs, /dev/stdin; text and binary PLY),
# --input-format, extra columns, --columns and headers, the progress line
# (--progress: phases named, width, none with --quiet), --stream with
# --set-hash in every mode, --memory-limit.
set -u

FRONTDT=${1:?usage: test_cli.sh FRONTDT BAD_DIR}
BAD=${2:?usage: test_cli.sh FRONTDT BAD_DIR}
case $FRONTDT in /*) ;; *) FRONTDT=$PWD/$FRONTDT ;; esac
case $BAD in /*) ;; *) BAD=$PWD/$BAD ;; esac

WORK=$(mktemp -d "${TMPDIR:-/tmp}/fdt_test_cli.XXXXXX") || exit 1
# shellcheck disable=SC2317 # called by the EXIT trap
cleanup() { rm -rf "$WORK"; }
trap cleanup EXIT
cd "$WORK" || exit 1

FAILS=0
fail() { echo "FAIL: $*" >&2; FAILS=$((FAILS + 1)); }
note() { echo "note: $*" >&2; }

# run NAME CMD...: runs CMD, stdout in NAME.out, stderr in NAME.err,
# exit status in $RC.
run() {
    local name=$1
    shift
    "$@" >"$name.out" 2>"$name.err"
    RC=$?
}

expect_rc() { # NAME WANT
    if [ "$RC" != "$2" ]; then
        fail "$1: exit $RC, want $2; stderr: $(head -c 600 "$1.err")"
        return 1
    fi
    return 0
}

expect_in() { # NAME FILE(out|err) SUBSTRING
    if ! grep -qF -- "$3" "$1.$2"; then
        fail "$1: std$2 lacks '$3'; it says: $(head -c 600 "$1.$2")"
    fi
}

# No entries at all in directory $1 (hidden temporaries included).
expect_empty_dir() { # NAME DIR
    local left
    left=$(ls -A "$2")
    if [ -n "$left" ]; then
        fail "$1: left behind in $2: $left"
        rm -rf "${2:?}"/* "${2:?}"/.[!.]* 2>/dev/null
    fi
}

# Random points (fixed seed) in the unit cube, %.17g so they read back
# exactly. mawk and gawk draw different numbers; each run is consistent.
gen_points() { # N SEED
    awk -v n="$1" -v seed="$2" 'BEGIN {
        srand(seed)
        for (i = 0; i < n; i++)
            printf "%.17g %.17g %.17g\n", rand(), rand(), rand()
    }'
}

# ---------------------------------------------------------------------------
# --help, --version, usage errors
# ---------------------------------------------------------------------------
run help "$FRONTDT" --help
expect_rc help 0 && expect_in help out "Exit codes"
expect_in help out "--demo"
run help_short "$FRONTDT" -h
expect_rc help_short 0
run version "$FRONTDT" --version
expect_rc version 0 && expect_in version out "frontdt "

gen_points 300 11 >pts.xyz

usage_case() { # NAME SUBSTRING ARGS...
    local name=$1 msg=$2
    shift 2
    run "$name" "$FRONTDT" "$@"
    expect_rc "$name" 1 && expect_in "$name" err "$msg"
}
usage_case u_noargs "no input file"
usage_case u_unknown "unknown" --frobnicate pts.xyz
usage_case u_unknown_short "unknown option -Z" -Z pts.xyz
usage_case u_two_inputs "one input file only" pts.xyz pts.xyz
usage_case u_threads "--threads" -t abc pts.xyz
usage_case u_threads_neg "--threads" --threads=-2 pts.xyz
usage_case u_mode "unknown mode" --mode turbo pts.xyz
usage_case u_o_missing "needs a value" pts.xyz -o
usage_case u_demo_input "--demo takes no input" --demo 1000 pts.xyz
usage_case u_demo_word "--demo takes no input" --demo abc
usage_case u_demo_eq "--demo wants a point count" --demo=12x
usage_case u_pin_arg "option --pin=3" --pin=3 pts.xyz
usage_case u_long_missing "option --threads needs a value" pts.xyz --threads
usage_case u_o_nine "-o given more than 8 times" pts.xyz -o a1.tets -o a2.tets -o a3.tets \
    -o a4.tets -o a5.tets -o a6.tets -o a7.tets -o a8.tets -o a9.tets
usage_case u_demo_format "need an input file, not --demo" --demo 100 --input-format xyz
usage_case u_two_stdout "both want standard output" pts.xyz -o - --stats-json -
usage_case u_stdout_tetgen "cannot go to standard output" pts.xyz -o - --format tetgen
# --format against the output's extension (issue 34 item 5): refused when
# it names another format, before anything is written; fine when they
# agree (msh2 and msh share .msh) or the name has no known extension
usage_case u_format_ext "--format msh2 contradicts the extension of m.vtu (vtu)" pts.xyz \
    -o m.msh -o m22.msh --format msh2 -o m.vtu
[ ! -e m.msh ] && [ ! -e m22.msh ] && [ ! -e m.vtu ] || fail "u_format_ext wrote an output"
usage_case u_format_ext2 "--format vtk contradicts the extension of m.ele (tetgen)" pts.xyz \
    -o m.ele --format vtk
for ok in "-o f22.msh --format msh2" "-o f.ele --format tetgen" "-o f.dat --format vtk" \
    "-o f.vtk --format vtk"; do
    # shellcheck disable=SC2086 # the words of each case
    run format_ok "$FRONTDT" pts.xyz -q $ok
    expect_rc format_ok 0
done
[ -s f22.msh ] && [ -s f.ele ] && [ -s f.dat ] && [ -s f.vtk ] || fail "format_ok: an output is missing"
rm -f f22.msh f.node f.ele f.face f.neigh f.dat f.vtk
# --help and --version that cannot be written: exit 5, the reason said.
run help_full bash -c '"$1" --help >/dev/full' _ "$FRONTDT"
expect_rc help_full 5 && expect_in help_full err "stdout:"
run version_full bash -c '"$1" --version >/dev/full' _ "$FRONTDT"
expect_rc version_full 5
# An output name too long for the file system's paths: exit 5, nothing made.
mkdir -p out
long_name=out/$(printf 'n%.0s' $(seq 1 5000)).tets
run o_toolong "$FRONTDT" pts.xyz -o "$long_name"
expect_rc o_toolong 5 && expect_in o_toolong err "File name too long"
expect_empty_dir o_toolong out
# A usage error must not create the output.
mkdir -p out
run u_nooutput "$FRONTDT" --mode turbo pts.xyz -o out/x.tets
expect_rc u_nooutput 1
expect_empty_dir u_nooutput out

# ---------------------------------------------------------------------------
# Hostile inputs: tests/bad/EXPECTED.txt
# ---------------------------------------------------------------------------
if [ ! -f "$BAD/EXPECTED.txt" ]; then
    fail "no $BAD/EXPECTED.txt"
else
    rows=0
    while IFS= read -r line || [ -n "$line" ]; do
        case $line in '' | '#'*) continue ;; esac
        if [[ $line == *$'\t'* ]]; then
            IFS=$'\t' read -r file code msg <<<"$line"
        else
            read -r file code msg <<<"$line"
        fi
        rows=$((rows + 1))
        # Surrounding quotes on the message are allowed.
        msg=${msg#\"}
        msg=${msg%\"}
        name="bad_$rows"
        rm -rf out && mkdir out
        run "$name" "$FRONTDT" "$BAD/$file" -o out/mesh.tets
        if [ "$RC" != "$code" ]; then
            fail "bad/$file: exit $RC, want $code; stderr: $(head -c 600 "$name.err")"
        elif ! grep -qF -- "$msg" "$name.err"; then
            fail "bad/$file: stderr lacks '$msg': $(head -c 600 "$name.err")"
        fi
        if ! grep -q '^frontdt: ' "$name.err"; then
            fail "bad/$file: message without the 'frontdt: ' prefix"
        fi
        expect_empty_dir "bad/$file" out
        # The same with a TetGen set: four files, none may appear.
        run "${name}_ele" "$FRONTDT" "$BAD/$file" -o out/mesh.ele
        [ "$RC" = "$code" ] || fail "bad/$file (.ele): exit $RC, want $code"
        expect_empty_dir "bad/$file (.ele)" out
    done <"$BAD/EXPECTED.txt"
    [ "$rows" -gt 0 ] || fail "EXPECTED.txt has no rows"
fi

# Inputs the reader accepts but the library cannot triangulate: exit 2,
# the library's diagnostic, nothing written.
awk 'BEGIN { srand(4); for (i = 0; i < 50; i++) printf "%.17g %.17g 0.5\n", rand(), rand() }' >flat.xyz
printf '0 0 0\n1 0 0\n0 1 0\n1 0 0\n0 0 0\n' >three.xyz
printf '0 0 0\n1 1 1\n2 2 2\n3 3 3\n4 4 4\n' >line.xyz
for f in flat three line; do
    rm -rf out && mkdir out
    run "degenerate_$f" "$FRONTDT" "$f.xyz" -o out/mesh.ele --check
    expect_rc "degenerate_$f" 2 && expect_in "degenerate_$f" err "frontdt: $f.xyz: "
    expect_empty_dir "degenerate_$f" out
done

# ---------------------------------------------------------------------------
# Standard input, --input-format, columns, headers, the progress line
# ---------------------------------------------------------------------------
gen_points 300 11 >io.xyz
run io_ref "$FRONTDT" --hash io.xyz
expect_rc io_ref 0
io_hash=$(grep '^hash:' io_ref.out)
# '-' from a pipe (not seekable), and a named pipe and /dev/stdin by path.
cat io.xyz | "$FRONTDT" --hash --input-format xyz - >io_pipe.out 2>io_pipe.err
RC=$?
expect_rc io_pipe 0 && expect_in io_pipe out "$io_hash"
mkfifo io.fifo
cat io.xyz >io.fifo &
run io_fifo "$FRONTDT" --hash --input-format xyz io.fifo
expect_rc io_fifo 0 && expect_in io_fifo out "$io_hash"
wait
run io_devstdin "$FRONTDT" --hash --input-format txt /dev/stdin <io.xyz
expect_rc io_devstdin 0 && expect_in io_devstdin out "$io_hash"
# --format names the input's format too (issue 17's spelling), before or
# after the input, and still the output's with an output name.
cat io.xyz | "$FRONTDT" --hash --format xyz - -o io_fmt.vtu --format vtu >io_fmt.out 2>io_fmt.err
RC=$?
expect_rc io_fmt 0 && expect_in io_fmt out "$io_hash"
[ -s io_fmt.vtu ] || fail "io_fmt: --format xyz with -o io_fmt.vtu wrote no mesh"
run io_fmtbad "$FRONTDT" --format las io.xyz
expect_rc io_fmtbad 1 && expect_in io_fmtbad err "unknown format 'las' (input: xyz"
# Binary PLY from a pipe.
awk 'BEGIN { printf "ply\nformat ascii 1.0\nelement vertex 300\nproperty double x\nproperty double y\nproperty double z\nend_header\n" } { print }' io.xyz >io_ascii.ply
cat io_ascii.ply | "$FRONTDT" --hash --input-format ply - >io_ply.out 2>io_ply.err
RC=$?
expect_rc io_ply 0 && expect_in io_ply out "$io_hash"
if command -v python3 >/dev/null; then
    python3 -c '
import struct, sys
pts = [tuple(float(v) for v in l.split()) for l in open("io.xyz")]
sys.stdout.buffer.write(b"ply\nformat binary_big_endian 1.0\nelement vertex %d\nproperty double x\nproperty double y\nproperty double z\nend_header\n" % len(pts))
for p in pts:
    sys.stdout.buffer.write(struct.pack(">3d", *p))' | "$FRONTDT" --hash --input-format ply - >io_bply.out 2>io_bply.err
    RC=$?
    expect_rc io_bply 0 && expect_in io_bply out "$io_hash"
fi
# Usage errors (exit 1): '-' without a format, an unknown format, bad
# --columns, --columns for .node/.ply; nothing read.
run io_noformat "$FRONTDT" - </dev/null
expect_rc io_noformat 1 && expect_in io_noformat err "needs --input-format"
run io_badformat "$FRONTDT" --input-format las io.xyz
expect_rc io_badformat 1 && expect_in io_badformat err "unknown input format 'las'"
for bad in 0,1,2 1,2 1,2,3,4 1,1,2 1,2,1 1,2,2 a,b,c 1,,2 ,1,2 12345678901234567,1,2; do
    run io_badcols "$FRONTDT" --columns "$bad" io.xyz
    expect_rc io_badcols 1 && expect_in io_badcols err "--columns wants three"
done
printf '4\n' >io.node
run io_colsnode "$FRONTDT" --columns 2,3,4 io.node
expect_rc io_colsnode 1 && expect_in io_colsnode err "--columns applies to .xyz"
# Bad input read from stdin is named "stdin" (exit 2).
printf '0 0 0\n1 0 x\n' | "$FRONTDT" --input-format xyz - >io_stdinbad.out 2>io_stdinbad.err
RC=$?
expect_rc io_stdinbad 2 && expect_in io_stdinbad err "stdin:2: not a number: 'x'"
# Lidar-style CSV: a header, an id and a name before x y z, colour after:
# --columns 3,4,5 gives the plain file's mesh; extra columns alone are
# skipped without --columns.
awk 'BEGIN { print "id,name,X,Y,Z,R,G,B" } { printf "%d,p%d,%s,%s,%s,255,0,0\n", NR, NR, $1, $2, $3 }' io.xyz >io_lidar.csv
run io_csv "$FRONTDT" --hash --columns 3,4,5 io_lidar.csv
expect_rc io_csv 0 && expect_in io_csv out "$io_hash"
# A European export (issue 34): decimal commas between blanks are refused,
# naming the line (they read as other numbers before), and read with
# --decimal-comma as the same mesh; ';' fields likewise with --delimiter.
awk '{ gsub(/\./, ",") } 1' io.xyz >io_eu.xyz
run io_eu "$FRONTDT" --hash io_eu.xyz
expect_rc io_eu 2 && expect_in io_eu err "io_eu.xyz:1: commas between digits and blanks between fields: pass --decimal-comma"
run io_eu_dc "$FRONTDT" --hash --decimal-comma io_eu.xyz
expect_rc io_eu_dc 0 && expect_in io_eu_dc out "$io_hash"
awk 'BEGIN { print "X;Y;Z" } { gsub(/\./, ","); print $1 ";" $2 ";" $3 }' io.xyz >io_eu.csv
run io_eu_semi "$FRONTDT" --hash io_eu.csv
expect_rc io_eu_semi 2 && expect_in io_eu_semi err "io_eu.csv:2: fields separated by ';'" &&
  expect_in io_eu_semi err "--delimiter ';' --decimal-comma"
run io_eu_semi_ok "$FRONTDT" --hash --delimiter ';' --decimal-comma io_eu.csv
expect_rc io_eu_semi_ok 0 && expect_in io_eu_semi_ok out "$io_hash"
run io_eu_both "$FRONTDT" --decimal-comma --delimiter , io_eu.xyz
expect_rc io_eu_both 1 && expect_in io_eu_both err "a comma cannot be both"
run io_eu_node "$FRONTDT" --decimal-comma io.node
expect_rc io_eu_node 1 && expect_in io_eu_node err "--delimiter and --decimal-comma apply to .xyz"
awk '{ print $0, 17, 200, 100, 50 }' io.xyz >io_extra.txt
run io_extra "$FRONTDT" --hash io_extra.txt
expect_rc io_extra 0 && expect_in io_extra out "$io_hash"
awk 'NR == 5 { print $1, $2, $3; next } { print $0, 17 }' io.xyz >io_ragged.xyz
run io_ragged "$FRONTDT" io_ragged.xyz
expect_rc io_ragged 2 && expect_in io_ragged err "io_ragged.xyz:5: expected 4 columns as on the first line, found 3"
run io_fewcols "$FRONTDT" --columns 3,4,9 io_lidar.csv
expect_rc io_fewcols 2 && expect_in io_fewcols err "io_lidar.csv:2: columns 3,4,9 need 9 fields, found 8"
# The progress line, forced onto a file (stderr is no terminal here): each
# phase named; none without --progress, none with --quiet.
run io_prog "$FRONTDT" --progress --hash io.xyz -o out/io_prog.tets
expect_rc io_prog 0
for phase in read parse merge triangulate sort write; do
    expect_in io_prog err "frontdt: $phase"
done
rm -f out/io_prog.tets
run io_noprog "$FRONTDT" --hash io.xyz
grep -q 'frontdt: read' io_noprog.err && fail "io_noprog: a progress line without --progress on a non-terminal"
run io_quietprog "$FRONTDT" --progress --quiet --hash io.xyz
[ -s io_quietprog.err ] && fail "io_quietprog: --quiet still drew: $(head -c 200 io_quietprog.err)"
# The line fits $COLUMNS (no terminal to ask): every redraw, and a narrow
# one drops the bar but keeps the phase.
COLUMNS=50 "$FRONTDT" --progress --demo 20000 >io_w50.out 2>io_w50.err
tr '\r' '\n' <io_w50.err | awk 'length($0) > 49 { bad = 1 } END { exit bad }' ||
    fail "io_w50: a progress line wider than COLUMNS=50 - 1"
COLUMNS=20 "$FRONTDT" --progress --demo 2000 >io_w20.out 2>io_w20.err
grep -q 'frontdt: trian' io_w20.err || fail "io_w20: no phase on a 20-column line"

# ---------------------------------------------------------------------------
# Output refusals before any computation
# ---------------------------------------------------------------------------
rm -rf out && mkdir out
start=$(date +%s%N)
run ext "$FRONTDT" --demo 3000000 -o out/mesh.xyz
end=$(date +%s%N)
expect_rc ext 1 && expect_in ext err "frontdt: out/mesh.xyz: unknown output format"
ms=$(((end - start) / 1000000))
[ "$ms" -lt 2000 ] || fail "unknown output extension took ${ms} ms: not refused up front"
expect_empty_dir ext out

start=$(date +%s%N)
run nodir "$FRONTDT" --demo 3000000 -o out/no/such/dir/mesh.tets
end=$(date +%s%N)
expect_rc nodir 5 &&
    expect_in nodir err "cannot create output out/no/such/dir/mesh.tets: folder out/no/such/dir does not exist"
ms=$(((end - start) / 1000000))
[ "$ms" -lt 2000 ] || fail "missing output directory took ${ms} ms: not refused up front"
expect_empty_dir nodir out
# ... also for a normal input file, and a TetGen set.
run nodir2 "$FRONTDT" pts.xyz -o out/nodir/mesh.ele
expect_rc nodir2 5 && expect_in nodir2 err "cannot create output out/nodir/mesh.ele: folder out/nodir does not exist"
expect_empty_dir nodir2 out
# ... and a polyMesh whose case has no constant/ (issue 34 item 8: the
# message names the output's role and the missing folder)
mkdir out/case
run nodir3 "$FRONTDT" pts.xyz -o out/case/constant/polyMesh
expect_rc nodir3 5 &&
    expect_in nodir3 err "cannot create output out/case/constant/polyMesh: folder out/case/constant does not exist"
rmdir out/case
expect_empty_dir nodir3 out
# A regular file in place of the directory.
touch out/plain
run notdir "$FRONTDT" pts.xyz -o out/plain/mesh.vtu
expect_rc notdir 5 && expect_in notdir err "cannot create output out/plain/mesh.vtu: out/plain is not a folder"
rm -f out/plain
expect_empty_dir notdir out
# The output is a directory.
mkdir out/isdir.tets
run isdir "$FRONTDT" pts.xyz -o out/isdir.tets
expect_rc isdir 5 && expect_in isdir err "cannot create output out/isdir.tets: a folder has that name"
rmdir out/isdir.tets
expect_empty_dir isdir out
# Replacing an existing output (issue 34 item 6): allowed by default,
# refused by --no-clobber before any work (exit 5, the file named, every
# file as it was), for any file of a set and for --stats-json; a run
# whose outputs are all new is not refused.
printf 'old\n' >out/c.vtk
run clob_default "$FRONTDT" pts.xyz -q -o out/c.vtk
expect_rc clob_default 0
grep -q '^old$' out/c.vtk && fail "clob_default: the existing out/c.vtk was not replaced"
printf 'old\n' >out/c.vtk
start=$(date +%s%N)
run clob "$FRONTDT" --demo 3000000 --no-clobber -o out/new.vtu -o out/c.vtk
end=$(date +%s%N)
expect_rc clob 5 && expect_in clob err "output out/c.vtk exists; --no-clobber keeps it"
ms=$(((end - start) / 1000000))
[ "$ms" -lt 2000 ] || fail "--no-clobber took ${ms} ms: not refused up front"
[ "$(cat out/c.vtk)" = old ] || fail "clob: out/c.vtk changed"
[ ! -e out/new.vtu ] || fail "clob: out/new.vtu written"
rm -f out/c.vtk
printf 'old\n' >out/c.neigh
run clob_set "$FRONTDT" pts.xyz --no-clobber -o out/c.ele
expect_rc clob_set 5 && expect_in clob_set err "output out/c.neigh (written with -o out/c.ele) exists"
[ "$(cat out/c.neigh)" = old ] || fail "clob_set: out/c.neigh changed"
rm -f out/c.neigh
printf '{}\n' >out/c.json
run clob_json "$FRONTDT" pts.xyz --no-clobber --stats-json out/c.json
expect_rc clob_json 5 && expect_in clob_json err "--stats-json file out/c.json exists"
rm -f out/c.json
run clob_new "$FRONTDT" pts.xyz -q --no-clobber -o out/c.ele --stats-json out/c.json
expect_rc clob_new 0
[ -s out/c.node ] && [ -s out/c.neigh ] && [ -s out/c.json ] || fail "clob_new: outputs missing"
rm -f out/c.*
expect_empty_dir clob out
# --stats-json into a missing directory is refused up front as well.
run jsondir "$FRONTDT" pts.xyz --stats-json out/no/stats.json
expect_rc jsondir 5 &&
    expect_in jsondir err "cannot create --stats-json file out/no/stats.json: folder out/no does not exist"
expect_empty_dir jsondir out

# ---------------------------------------------------------------------------
# Never overwrite an input (issue 17 item 1)
# ---------------------------------------------------------------------------
# Every output family against every way of naming the input: the same path,
# "./", "dir/../", absolute paths, a symbolic link to the input (as the
# input or as the output), a hard link, the .ele family's .node sibling,
# and --stats-json on the input or on one of the mesh's files. Each must
# exit 1 before any work with a message naming both files, leave the
# input's bytes as they were (cmp against a saved copy) and leave the
# directory as it was: no temporary, no output, no link turned into a file.
rm -rf ow ow_saved && mkdir -p ow/sub ow_saved
# What a rewrite of a .node file would lose: a comment, 1-based numbering,
# an attribute and a boundary marker.
{
    echo "# kept: comment, 1-based numbering, an attribute, a marker"
    echo "300 3 1 1"
    awk '{ printf "%d %s %s %s 0.5 %d\n", NR, $1, $2, $3, NR % 3 }' pts.xyz
} >ow/m.node
cp pts.xyz ow/r.xyz
# Inputs named as the .tets/.vtu/.vtk output would be (the reader would
# refuse these extensions, but only after the check, which comes first).
for f in tets vtu vtk; do cp pts.xyz "ow/m.$f"; done
cp ow/m.node ow/r.xyz ow/m.tets ow/m.vtu ow/m.vtk ow_saved/
ow_listing() { find ow -printf '%y %p\n' | LC_ALL=C sort; }
ow_listing >ow_before.txt

# ow_case NAME OUTNAME INNAME ARGS...: exit 1, a message naming OUTNAME
# and the input INNAME, and nothing in ow/ changed.
ow_case() {
    local name=$1 outname=$2 inname=$3 f
    shift 3
    run "$name" "$FRONTDT" "$@"
    expect_rc "$name" 1
    expect_in "$name" err "frontdt: "
    expect_in "$name" err "$outname"
    expect_in "$name" err "would overwrite the $inname"
    for f in m.node r.xyz m.tets m.vtu m.vtk; do
        if ! cmp -s "ow/$f" "ow_saved/$f"; then
            fail "$name: the input ow/$f was changed"
            cp "ow_saved/$f" "ow/$f"
        fi
    done
    if ! ow_listing | cmp -s - ow_before.txt; then
        fail "$name: ow/ changed: $(ow_listing | diff ow_before.txt - | tr '\n' ' ')"
    fi
}

for fam in tets ele vtu vtk; do
    if [ "$fam" = ele ]; then
        clash=node # the file of the set that can be an input
        real=ow/m.node # a readable input for the link cases
    else
        clash=$fam
        real=ow/r.xyz
    fi
    in=ow/m.$clash
    rb=${real#ow/}
    ow_case "ow_${fam}_same" "output ow/m.$clash" "input $in" "$in" -o "ow/m.$fam"
    ow_case "ow_${fam}_dot" "output ./ow/m.$clash" "input $in" "$in" -o "./ow/m.$fam"
    ow_case "ow_${fam}_dotdot" "output ow/sub/../m.$clash" "input $in" "$in" -o "ow/sub/../m.$fam"
    ow_case "ow_${fam}_abs_out" "output $PWD/ow/m.$clash" "input $in" "$in" -o "$PWD/ow/m.$fam"
    ow_case "ow_${fam}_abs_in" "output ow/m.$clash" "input $PWD/$in" "$PWD/$in" -o "ow/m.$fam"
    ow_case "ow_${fam}_dot_in" "output ow/m.$clash" "input ./$in" "./$in" -o "ow/m.$fam"
    # The input named through a symbolic link (and through a linked
    # directory): the output is the file behind it.
    ln -s "m.$clash" "ow/lin.$clash"
    ln -s .. ow/sub/up
    ow_listing >ow_before.txt
    ow_case "ow_${fam}_in_link" "output ow/m.$clash" "input ow/lin.$clash" "ow/lin.$clash" -o "ow/m.$fam"
    ow_case "ow_${fam}_in_dirlink" "output ow/m.$clash" "input ow/sub/up/m.$clash" \
        "ow/sub/up/m.$clash" -o "ow/m.$fam"
    # The output (or, for .ele, its .node) a symbolic link to the input.
    ln -s "$rb" "ow/lo.$clash"
    # ... and a hard link to it; also the input named by a hard link.
    ln "$real" "ow/hl.$clash"
    ln "$in" "ow/hin.$clash"
    ow_listing >ow_before.txt
    ow_case "ow_${fam}_out_link" "output ow/lo.$clash" "input $real" "$real" -o "ow/lo.$fam"
    ow_case "ow_${fam}_hard_link" "output ow/hl.$clash" "input $real" "$real" -o "ow/hl.$fam"
    ow_case "ow_${fam}_hard_link_in" "output ow/m.$clash" "input ow/hin.$clash" \
        "ow/hin.$clash" -o "ow/m.$fam"
    # --stats-json on the input, by its name or through a link, beside a
    # legitimate mesh output.
    ow_case "ow_${fam}_json" "--stats-json file $real" "input $real" "$real" \
        -o "ow/fine.$fam" --stats-json "$real"
    ow_case "ow_${fam}_json_link" "--stats-json file ow/lo.$clash" "input $real" "$real" \
        -o "ow/fine.$fam" --stats-json "ow/lo.$clash"
    # --stats-json on a file of the mesh's own set (written after it).
    ow_case "ow_${fam}_json_out" "--stats-json file ./ow/s.$clash" "output ow/s.$clash" "$real" \
        -o "ow/s.$fam" --stats-json "./ow/s.$clash"
    rm -f "ow/lin.$clash" ow/sub/up "ow/lo.$clash" "ow/hl.$clash" "ow/hin.$clash"
    ow_listing >ow_before.txt
done
# The .ele family's siblings: "-o m.ele" writes m.node, whatever the case
# of ".ele"; the message says which -o writes it.
ow_case ow_sibling "output ow/m.node (written with -o ow/m.ele)" "input ow/m.node" ow/m.node -o ow/m.ele
ow_case ow_sibling_case "output ow/m.node (written with -o ow/m.ELE)" "input ow/m.node" ow/m.node -o ow/m.ELE
ow_case ow_sibling_neigh "--stats-json file ow/d.neigh" "output ow/d.neigh (written with -o ow/d.ele)" \
    --demo 3000000 -o ow/d.ele --stats-json ow/d.neigh
# "-o m.face" (or .node, .neigh) is no output format at all: refused as
# such, the input untouched.
for ext in face node neigh; do
    run "ow_$ext" "$FRONTDT" ow/m.node -o "ow/m.$ext"
    expect_rc "ow_$ext" 1 && expect_in "ow_$ext" err "ow/m.$ext: unknown output format"
    cmp -s ow/m.node ow_saved/m.node || fail "ow_$ext: ow/m.node was changed"
done
ow_listing | cmp -s - ow_before.txt || fail "ow: unknown formats left files in ow/"

# Controls: outputs beside the input (another name, or the same name in
# another directory) and --stats-json beside it still work, and leave the
# input as it was.
for fam in tets ele vtu vtk; do
    if [ "$fam" = ele ]; then real=ow/m.node; else real=ow/r.xyz; fi
    run "ow_ok_$fam" "$FRONTDT" "$real" -o "ow/beside.$fam" --stats-json ow/beside.json --quiet
    expect_rc "ow_ok_$fam" 0
    [ -s "ow/beside.$fam" ] || fail "ow_ok_$fam: no ow/beside.$fam"
    [ -s ow/beside.json ] || fail "ow_ok_$fam: no ow/beside.json"
    base=${real#ow/}
    run "ow_ok_sub_$fam" "$FRONTDT" "$real" -o "ow/sub/${base%.*}.$fam" --quiet
    expect_rc "ow_ok_sub_$fam" 0
    [ -s "ow/sub/${base%.*}.$fam" ] || fail "ow_ok_sub_$fam: no ow/sub/${base%.*}.$fam"
    cmp -s "$real" "ow_saved/$base" || fail "ow_ok_$fam: $real was changed"
done
[ "$(head -n1 ow/beside.node)" = "300 3 0 0" ] || fail "ow_ok_ele: no .node written beside the input"
compgen -G "ow/.*.tmp.*" >/dev/null && fail "ow: temporary files left: $(ls -A ow)"
rm -rf ow ow_saved

# ---------------------------------------------------------------------------
# Write errors during the run: reported (exit 5), never ignored
# ---------------------------------------------------------------------------
# A file size limit makes write() fail part-way with EFBIG, as a full disk
# fails with ENOSPC; frontdt ignores SIGXFSZ so the error reaches the
# writer, which removes its temporaries. Every format, in a subshell so the
# limit stays there (16 KiB: the 300-point meshes are larger).
for fmt in tets ele vtu vtk; do
    rm -rf out && mkdir out
    (
        trap - XFSZ
        ulimit -f 16
        exec "$FRONTDT" pts.xyz -o "out/big.$fmt" --quiet
    ) >"fsize_$fmt.out" 2>"fsize_$fmt.err"
    RC=$?
    # (.ele: the first of the four files, big.node, is the one that fails)
    expect_rc "fsize_$fmt" 5 && expect_in "fsize_$fmt" err "frontdt: out/big."
    expect_in "fsize_$fmt" err ": File too large"
    expect_empty_dir "fsize_$fmt (file size limit)" out
done
# In the middle of a TetGen set: 20 KiB lets the 19 KB .node through and
# stops the 34 KB .ele, so one file of the set is complete (as a
# temporary) when the next fails: both must go, and the message names the
# file that failed.
rm -rf out && mkdir out
[ "$(wc -c <pts.xyz)" -gt 0 ] || fail "no pts.xyz"
(
    trap - XFSZ
    ulimit -f 20
    exec "$FRONTDT" pts.xyz -o out/mid.ele --quiet
) >fsize_mid.out 2>fsize_mid.err
RC=$?
expect_rc fsize_mid 5 && expect_in fsize_mid err "out/mid.ele: File too large"
grep -q "mid.node" fsize_mid.err && fail "fsize_mid: the .node failed, not the middle of the set"
expect_empty_dir "fsize_mid (the .ele of a TetGen set)" out
# Without the limit the same set is written, the .node within the limit.
run fsize_mid_ok "$FRONTDT" pts.xyz -o out/mid.ele --quiet
expect_rc fsize_mid_ok 0
[ "$(wc -c <out/mid.node)" -le 20480 ] && [ "$(wc -c <out/mid.ele)" -gt 20480 ] ||
    fail "fsize_mid: .node $(wc -c <out/mid.node) B, .ele $(wc -c <out/mid.ele) B: the limit no longer falls between them"
rm -rf out && mkdir out
# stdout on a full device: the summary cannot be written.
run full_stdout bash -c '"$1" "$2" --hash >/dev/full' _ "$FRONTDT" pts.xyz
expect_rc full_stdout 5 && expect_in full_stdout err "stdout: No space left on device"
# --stats-json on a full device, through a symbolic link: exit 5, and the
# link is not removed (only a regular file of ours is).
rm -rf out && mkdir out
ln -s /dev/full out/full.json
run full_json "$FRONTDT" pts.xyz --stats-json out/full.json --quiet
expect_rc full_json 5 && expect_in full_json err "out/full.json: No space left on device"
[ -L out/full.json ] || fail "full_json: the symbolic link to /dev/full was removed"
rm -f out/full.json
# --stats-json - on a full standard output: exit 5, stdout named.
run full_json_stdout bash -c '"$1" "$2" --stats-json - --quiet >/dev/full' _ "$FRONTDT" pts.xyz
expect_rc full_json_stdout 5 && expect_in full_json_stdout err "stdout: No space left on device"
# --stats-json to a file past the file size limit (1 KiB; the JSON is
# larger): its commit fails, exit 5, nothing left, an old file kept.
printf 'old\n' >out/old.json
(
    trap - XFSZ
    ulimit -f 1
    exec "$FRONTDT" pts.xyz --stats-json out/old.json --quiet
) >fsize_json.out 2>fsize_json.err
RC=$?
expect_rc fsize_json 5 && expect_in fsize_json err "out/old.json: File too large"
[ "$(cat out/old.json)" = old ] || fail "fsize_json: out/old.json was changed"
rm -f out/old.json
expect_empty_dir fsize_json out

# ---------------------------------------------------------------------------
# Reading from a pipe and a FIFO: not seekable, not mapped; the same mesh
# ---------------------------------------------------------------------------
rm -rf out && mkdir out
run file_ref "$FRONTDT" pts.xyz --hash
expect_rc file_ref 0
href=$(grep '^hash: ' file_ref.out)
[ -n "$href" ] || fail "file_ref: no hash line"
# The format comes from the extension: a link named .xyz to /dev/stdin
# reads the pipe.
ln -sf /dev/stdin stdin.xyz
run pipe bash -c 'cat "$2" | "$1" stdin.xyz --hash -o out/pipe.tets' _ "$FRONTDT" pts.xyz
expect_rc pipe 0 && [ "$(grep '^hash: ' pipe.out)" = "$href" ] ||
    fail "pipe: '$(grep '^hash: ' pipe.out)' against the file's '$href'"
[ -s out/pipe.tets ] || fail "pipe: no out/pipe.tets"
mkfifo fifo.xyz
cat pts.xyz >fifo.xyz &
catpid=$!
run fifo "$FRONTDT" fifo.xyz --hash
wait "$catpid"
expect_rc fifo 0 && [ "$(grep '^hash: ' fifo.out)" = "$href" ] ||
    fail "fifo: '$(grep '^hash: ' fifo.out)' against the file's '$href'"
# A hostile input through a pipe: its error and exit code as from a file
# (a NaN names line 3).
run pipe_bad bash -c 'printf "0 0 0\n1 0 0\nnan 1 0\n0 0 1\n" | "$1" stdin.xyz' _ "$FRONTDT"
expect_rc pipe_bad 2 && expect_in pipe_bad err "stdin.xyz:3: not a finite number"
rm -f fifo.xyz stdin.xyz

# ---------------------------------------------------------------------------
# A normal run: every format, --check, --stats, --hash
# ---------------------------------------------------------------------------
run normal "$FRONTDT" pts.xyz -o out/a.tets --check
expect_rc normal 0
expect_in normal out "check: passed"
expect_in normal out "tets: "
[ -s out/a.tets ] || fail "normal: no out/a.tets"
ntets=$(wc -l <out/a.tets)
grep -q "^tets: $ntets\$" normal.out || fail "normal: summary tet count is not the .tets line count $ntets"
# Canonical text: 4 ascending ids per line, lines in ascending order.
awk 'NF != 4 || !($1 < $2 && $2 < $3 && $3 < $4) || $4 >= 300 { bad = 1 }
     END { exit bad }' out/a.tets || fail "normal: malformed .tets line"
sort -c -n -k1,1 -k2,2 -k3,3 -k4,4 out/a.tets 2>/dev/null ||
    fail "normal: .tets lines not in ascending order"
# The .tets file of a random set in the cube: every point is a vertex.
used=$(tr ' ' '\n' <out/a.tets | sort -un | wc -l)
[ "$used" = 300 ] || fail "normal: $used of 300 points used"

for fmt in ele vtu vtk; do
    run "fmt_$fmt" "$FRONTDT" pts.xyz -o "out/a.$fmt" --quiet
    expect_rc "fmt_$fmt" 0
    [ -s "out/a.$fmt" ] || fail "no out/a.$fmt"
    [ -s "fmt_$fmt.out" ] && fail "fmt_$fmt: --quiet printed $(head -c 200 "fmt_$fmt.out")"
done
for f in node face neigh; do [ -s "out/a.$f" ] || fail "no out/a.$f"; done
[ "$(head -n1 out/a.node)" = "300 3 0 0" ] || fail ".node header: $(head -n1 out/a.node)"
[ "$(head -n1 out/a.ele)" = "$ntets 4 0" ] || fail ".ele header: $(head -n1 out/a.ele)"
[ "$(head -n1 out/a.neigh)" = "$ntets 4" ] || fail ".neigh header: $(head -n1 out/a.neigh)"
# The .ele tets are the .tets set.
tail -n +2 out/a.ele | awk '{ a[0] = $2; a[1] = $3; a[2] = $4; a[3] = $5
    for (i = 1; i < 4; i++) for (j = i; j > 0 && a[j] < a[j-1]; j--) {
        t = a[j]; a[j] = a[j-1]; a[j-1] = t }
    print a[0], a[1], a[2], a[3] }' | sort -n -k1,1 -k2,2 -k3,3 -k4,4 >ele_sorted.tets
cmp -s ele_sorted.tets out/a.tets || fail ".ele tet set differs from .tets"
# Neighbours are symmetric and -1 exactly on hull faces.
nhull=$(head -n1 out/a.face | awk '{ print $1 }')
awk -v nh="$nhull" 'NR == 1 { next }
    { for (k = 2; k <= 5; k++) { if ($k == -1) m++; else link[$1 " " $k] = 1 } }
    END { for (l in link) { split(l, p, " "); if (!((p[2] " " p[1]) in link)) bad = 1 }
          exit (bad || m != nh) }' out/a.neigh ||
    fail ".neigh not symmetric or its -1 count differs from $nhull hull faces"
grep -q '^POINTS 300 double$' out/a.vtk || fail ".vtk POINTS line"
grep -q "^CELLS $ntets $((5 * ntets))\$" out/a.vtk || fail ".vtk CELLS line"
grep -q 'type="UnstructuredGrid"' out/a.vtu || fail ".vtu header"
compgen -G "out/.*.tmp.*" >/dev/null && fail "temporary files left in out/: $(ls -A out)"

run stats "$FRONTDT" pts.xyz --stats --stats-json out/stats.json --hash
expect_rc stats 0
expect_in stats err "statistics"
expect_in stats out "hash: "
[ -s out/stats.json ] || fail "stats: no out/stats.json"
run stats_stdout "$FRONTDT" pts.xyz --stats-json - --hash
expect_rc stats_stdout 0
if [ -x /usr/bin/python3 ]; then
    /usr/bin/python3 - out/stats.json stats_stdout.out "$ntets" <<'EOF' || fail "stats JSON invalid or wrong"
import json, sys
a = json.load(open(sys.argv[1]))
b = json.load(open(sys.argv[2]))       # stdout must be the JSON object alone
n = int(sys.argv[3])
for d in (a, b):
    assert d["points"] == 300 and d["tets"] == n, d
    assert len(d["hash"]) == 16
assert a["hash"] == b["hash"]
EOF
fi

# ---------------------------------------------------------------------------
# Options: every search and mode gives the same hash; bad values are usage
# errors; statistics of a parallel run; JSON escaping; the progress bar
# ---------------------------------------------------------------------------
run opt_ref "$FRONTDT" pts.xyz --hash --quiet
expect_rc opt_ref 0
href=$(grep '^hash: ' opt_ref.out)
for opt in "--search auto" "--search kd" "--search mesh" "--mode auto" "--mode auto -t 2" \
    "-t 0" "--mode message -t 3 --search mesh"; do
    # shellcheck disable=SC2086
    run opt_ok "$FRONTDT" pts.xyz --hash --quiet $opt
    expect_rc opt_ok 0 && [ "$(grep '^hash: ' opt_ok.out)" = "$href" ] ||
        fail "'$opt': '$(grep '^hash: ' opt_ok.out)', want '$href'"
done
usage_case u_search "unknown search 'fast'" pts.xyz --search fast
usage_case u_mode "unknown mode 'gpu'" pts.xyz --mode gpu
usage_case u_o_twice "-o out/a.tets given twice" pts.xyz -o out/a.tets -o out/a.tets
usage_case u_o_empty "empty output file name" pts.xyz -o ""
usage_case u_json_empty "empty --stats-json file name" pts.xyz --stats-json ""
usage_case u_threads "--threads wants a count, not 'x'" pts.xyz -t x
# "--" ends the options: a file named like an option is an input.
cp pts.xyz ./-dash.xyz
run dashdash "$FRONTDT" --hash --quiet -- -dash.xyz
expect_rc dashdash 0 && [ "$(grep '^hash: ' dashdash.out)" = "$href" ] || fail "-- -dash.xyz"
rm -f ./-dash.xyz
# --stats of a parallel run: the per-thread table, one row per thread.
run pstats "$FRONTDT" pts.xyz --stats --mode message -t 3 --quiet
expect_rc pstats 0
expect_in pstats err "message"
# (the table's header, then rows "  0  points  tets ...": threads 0, 1, 2)
grep -q '^ *thread  *points  *tets' pstats.err &&
    [ "$(awk '/^ *thread  *points/ { t = 1; next } t && $1 ~ /^[0-9]+$/ { n++ } END { print n + 0 }' pstats.err)" = 3 ] ||
    fail "pstats: no per-thread table of 3 rows: $(tail -c 400 pstats.err)"
# JSON strings escape quotes, backslashes and control characters (an
# input named q"b\c<TAB>.xyz); python3 must parse the file back.
qname=$(printf 'q"b\\c\t.xyz')
cp pts.xyz "$qname"
run jsonesc "$FRONTDT" "$qname" --stats-json out/esc.json --quiet --mode shared -t 2
expect_rc jsonesc 0
if command -v python3 >/dev/null; then
    python3 -c 'import json, sys; d = json.load(open(sys.argv[1])); s = json.dumps(d)
assert "q\\\"b\\\\c\\t.xyz" in s, s[:300]' out/esc.json 2>jsonesc.py.err ||
        fail "jsonesc: out/esc.json does not hold the escaped name: $(head -c 300 jsonesc.py.err)"
else
    grep -qF 'q\"b\\c\u0009.xyz' out/esc.json || fail "jsonesc: name not escaped"
fi
rm -f "$qname"
# The progress bar is drawn only on a terminal: script(1) gives one.
if command -v script >/dev/null; then
    script -qec "$FRONTDT --demo 300000 --mode serial" /dev/null >tty.out 2>&1
    RC=$?
    [ "$RC" = 0 ] || fail "progress on a tty: exit $RC: $(head -c 300 tty.out)"
    grep -q 'frontdt: triangulate \[##*\.*\]  *[0-9]*%' tty.out ||
        fail "progress on a tty: no bar drawn: $(head -c 300 tty.out)"
    script -qec "$FRONTDT --demo 300000 --mode shared -t 2 --quiet" /dev/null >tty_q.out 2>&1
    grep -q '#' tty_q.out && fail "progress with --quiet on a tty: a bar was drawn"
fi

# ---------------------------------------------------------------------------
# Repeatability: byte-identical .tets and identical --hash
# ---------------------------------------------------------------------------
gen_points 2000 5 >rep.xyz
run rep1 "$FRONTDT" rep.xyz -o out/rep1.tets --hash
expect_rc rep1 0
run rep2 "$FRONTDT" rep.xyz -o out/rep2.tets --hash
expect_rc rep2 0
cmp -s out/rep1.tets out/rep2.tets || fail "repeated runs wrote different .tets"
h1=$(grep '^hash: ' rep1.out)
h2=$(grep '^hash: ' rep2.out)
[[ $h1 =~ ^hash:\ [0-9a-f]{16}$ ]] || fail "hash line malformed: '$h1'"
[ "$h1" = "$h2" ] || fail "repeated runs: '$h1' vs '$h2'"
for opt in "--mode serial" "-t 1" "-t 2" "--mode shared -t 3" "--mode message -t 2"; do
    # shellcheck disable=SC2086
    run rep_opt "$FRONTDT" rep.xyz -o out/rep_opt.tets --hash $opt
    # Every mode is built: a refusal (exit 1) is a failure like any other.
    expect_rc rep_opt 0 || continue
    cmp -s out/rep1.tets out/rep_opt.tets || fail "'$opt' wrote a different .tets"
    [ "$(grep '^hash: ' rep_opt.out)" = "$h1" ] || fail "'$opt' gave another hash"
done

# ---------------------------------------------------------------------------
# Input order: a shuffled copy gives the same tets once mapped back
# ---------------------------------------------------------------------------
# shuf.xyz line i is rep.xyz line perm[i] (0-based, perm.txt line i).
awk -v seed=99 '{ line[NR - 1] = $0 }
    END {
        n = NR; srand(seed)
        for (i = 0; i < n; i++) p[i] = i
        for (i = n - 1; i > 0; i--) {
            j = int(rand() * (i + 1)); t = p[i]; p[i] = p[j]; p[j] = t
        }
        for (i = 0; i < n; i++) { print line[p[i]] > "shuf.xyz"; print p[i] > "perm.txt" }
    }' rep.xyz
cmp -s shuf.xyz rep.xyz && fail "the shuffle did not shuffle"
run shuf "$FRONTDT" shuf.xyz -o out/shuf.tets
expect_rc shuf 0
awk 'NR == FNR { perm[FNR - 1] = $1; next }
    { for (k = 0; k < 4; k++) a[k] = perm[$(k + 1)]
      for (i = 1; i < 4; i++) for (j = i; j > 0 && a[j] < a[j-1]; j--) {
          t = a[j]; a[j] = a[j-1]; a[j-1] = t }
      print a[0], a[1], a[2], a[3] }' perm.txt out/shuf.tets |
    sort -n -k1,1 -k2,2 -k3,3 -k4,4 >shuf_mapped.tets
cmp -s shuf_mapped.tets out/rep1.tets || fail "shuffled input gives another tet set"

# ---------------------------------------------------------------------------
# Duplicates
# ---------------------------------------------------------------------------
{ cat pts.xyz; sed -n '3p;50p;50p;299p' pts.xyz; } >dup.xyz
run dup "$FRONTDT" dup.xyz -o out/dup.tets --check
expect_rc dup 0 && expect_in dup err "merged 4 duplicate points"
# The duplicates do not change the mesh (they map to their first index).
cmp -s out/dup.tets out/a.tets || fail "duplicates changed the tets"
run dup_quiet "$FRONTDT" dup.xyz --quiet
expect_rc dup_quiet 0
[ -s dup_quiet.err ] && fail "dup --quiet still said: $(cat dup_quiet.err)"
# --pin refused: hwloc told of cores whose CPUs (1000, 1001) this machine
# lacks, so binding fails; the run goes on unpinned, says so once, and
# the mesh is the same. (Without hwloc every --pin run is refused.)
run pin_refused env HWLOC_SYNTHETIC="core:2 pu:1(indexes=1000,1001)" HWLOC_THISSYSTEM=1 \
    "$FRONTDT" pts.xyz -t 2 --pin -o out/pin.tets
expect_rc pin_refused 0 && expect_in pin_refused err "ran unpinned"
[ "$(grep -c 'unpinned' pin_refused.err)" = 1 ] || fail "pin_refused: not said exactly once"
cmp -s out/pin.tets out/a.tets || fail "pin_refused: another mesh"
run pin_quiet env HWLOC_SYNTHETIC="core:2 pu:1(indexes=1000,1001)" HWLOC_THISSYSTEM=1 \
    "$FRONTDT" pts.xyz -t 2 --pin --quiet
expect_rc pin_quiet 0
[ -s pin_quiet.err ] && fail "pin --quiet still said: $(cat pin_quiet.err)"
# Which engine ran, in --stats (src/api/api.c, one_part): threads in the
# default mode build the mesh of every point and it is the answer; an
# explicit mode runs the parts. The same mesh either way.
run eng_one "$FRONTDT" pts.xyz -t 2 --stats -o out/eng1.tets
expect_rc eng_one 0 && expect_in eng_one err "engine            one-part"
run eng_parts "$FRONTDT" pts.xyz -t 2 --mode shared --stats -o out/eng2.tets
expect_rc eng_parts 0 && expect_in eng_parts err "engine            parts "
cmp -s out/eng1.tets out/a.tets || fail "eng_one: another mesh"
cmp -s out/eng2.tets out/a.tets || fail "eng_parts: another mesh"
run dup_vtu "$FRONTDT" dup.xyz -o out/dup.ele
expect_rc dup_vtu 0
[ "$(head -n1 out/dup.node)" = "304 3 0 0" ] || fail "dup .node must hold all 304 input points"

# ---------------------------------------------------------------------------
# --demo
# ---------------------------------------------------------------------------
run demo "$FRONTDT" --demo 20000
expect_rc demo 0
expect_in demo out "points: 20000"
expect_in demo out "tets: "
expect_in demo out "hull faces: "
expect_in demo out "tets/s: "
run demo_eq "$FRONTDT" --demo=20000 --hash -o out/demo.tets
expect_rc demo_eq 0
run demo_sep "$FRONTDT" --hash --demo 20000
expect_rc demo_sep 0
[ "$(grep '^hash: ' demo_eq.out)" = "$(grep '^hash: ' demo_sep.out)" ] ||
    fail "--demo=20000 and --demo 20000 differ"
dt=$(grep '^tets: ' demo.out | awk '{ print $2 }')
[ "$(wc -l <out/demo.tets)" = "$dt" ] || fail "--demo -o: .tets has not $dt lines"
run demo_small "$FRONTDT" --demo 3
expect_rc demo_small 2
# More points than memory holds: exit 4 (resources), said; past what a
# size_t of coordinates can count too. Under AddressSanitizer a request
# past its limit aborts unless malloc may return NULL, as it does unsanitized.
for big in 100000000000000 1000000000000000000; do
    run demo_huge env ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}allocator_may_return_null=1" \
        "$FRONTDT" --demo "$big" -q
    expect_rc demo_huge 4 && expect_in demo_huge err "demo: no memory for $big points"
done
usage_case u_demo_columns "need an input file, not --demo" --demo 100 --columns 1,2,3
# --stats-json of a demo: no input (null), the demo's count, the check.
run demo_json "$FRONTDT" --demo 1000 --check --stats-json out/demo.json -q
expect_rc demo_json 0
grep -q '"input": null, "demo": 1000,' out/demo.json || fail "demo_json: $(head -c 200 out/demo.json)"
grep -q '"check": "passed"' out/demo.json || fail "demo_json: no check passed"
# --stats says whether the threads were pinned: bound on a synthetic
# topology hwloc accepts any binding on (refused without hwloc), not asked
# without --pin.
run pin_stats env HWLOC_SYNTHETIC="core:2 pu:1" "$FRONTDT" pts.xyz --pin -t 2 --mode shared --stats -q
expect_rc pin_stats 0
grep -Eq 'pinned +(yes|refused \(ran unpinned\))$' pin_stats.out pin_stats.err ||
    fail "pin_stats: no pinned line: $(cat pin_stats.out)"
run nopin_stats "$FRONTDT" pts.xyz -t 2 --mode shared --stats -q
grep -Eq 'pinned +no$' nopin_stats.out nopin_stats.err || fail "nopin_stats: $(cat nopin_stats.out)"

# ---------------------------------------------------------------------------
# Signals: exit 6, no output, no temporary file
# ---------------------------------------------------------------------------
# Job control gives background jobs their own process group and keeps
# SIGINT deliverable (a non-interactive shell would start them with SIGINT
# ignored, and frontdt rightly leaves an inherited SIG_IGN alone).
set -m
for sig in TERM INT; do
    rm -rf out && mkdir out
    "$FRONTDT" --demo 3000000 -o out/big.tets >sig.out 2>sig.err &
    pid=$!
    sleep 1
    if ! kill -0 "$pid" 2>/dev/null; then
        wait "$pid"
        fail "SIG$sig: the run ended (exit $?) before the signal: $(head -c 300 sig.err)"
        continue
    fi
    kill -"$sig" "$pid"
    wait "$pid"
    RC=$?
    [ "$RC" = 6 ] || fail "SIG$sig during the run: exit $RC, want 6"
    expect_empty_dir "SIG$sig" out
done

# During the write itself: wait until a temporary exists, then signal.
# The TetGen set (four files) and the slow %.17g of .vtk give the window:
# 200,000 points write about 50 MB, hundreds of milliseconds against the
# 10 ms poll, so a temporary is always seen; not seeing one fails (the
# test would otherwise judge nothing).
for target in big.ele big.vtk; do
    rm -rf out && mkdir out
    "$FRONTDT" --demo 200000 -o "out/$target" --quiet >sig.out 2>sig.err &
    pid=$!
    seen=0
    while kill -0 "$pid" 2>/dev/null; do
        if compgen -G "out/.*.tmp.*" >/dev/null; then
            seen=1
            kill -TERM "$pid"
            break
        fi
        sleep 0.01
    done
    wait "$pid"
    RC=$?
    if [ "$seen" = 1 ]; then
        [ "$RC" = 6 ] || fail "SIGTERM while writing $target: exit $RC, want 6"
    else
        fail "the write of $target (exit $RC) finished before a temporary was seen"
    fi
    expect_empty_dir "SIGTERM while writing $target" out
done

# All-or-none outputs (issue 34 item 3). SIGINT while the second of four
# outputs is written: every old output must still be there, unchanged
# (the first one was already replaced before).
rm -rf out && mkdir out
"$FRONTDT" --demo 3000 -q -o out/x.msh -o out/x.vtk -o out/x.mesh -o out/x.ele ||
    fail "all-or-none: the old outputs were not written"
mkdir -p aon_old && cp -p out/x.* aon_old/
"$FRONTDT" --demo 200000 --quiet -o out/x.msh -o out/x.vtk -o out/x.mesh -o out/x.ele \
    >sig.out 2>sig.err &
pid=$!
seen=0
while kill -0 "$pid" 2>/dev/null; do
    if compgen -G "out/.x.vtk.tmp.*" >/dev/null; then
        seen=1
        kill -INT "$pid"
        break
    fi
    sleep 0.01
done
wait "$pid"
RC=$?
if [ "$seen" = 1 ]; then
    [ "$RC" = 6 ] || fail "SIGINT while writing the second output: exit $RC, want 6"
    for f in aon_old/x.*; do
        cmp -s "$f" "out/${f#aon_old/}" ||
            fail "SIGINT while writing the second output: out/${f#aon_old/} was replaced"
    done
    left=$(cd out && ls -A | tr '\n' ' ')
    [ "$left" = "x.ele x.face x.mesh x.msh x.neigh x.node x.vtk " ] ||
        fail "SIGINT while writing the second output left: $left"
else
    fail "all-or-none: the write (exit $RC) finished before the second output began"
fi
rm -rf aon_old out
set +m

# Every step of the final commit (FDT_TEST_COMMIT_FAULT=K:fail|signal,
# src/io/write/writer.c: each backup link, the journal, each rename, the
# commit point and the step after it) fails or is interrupted in turn;
# afterwards every output is either the old one or the new one, all
# alike (byte for byte against a run without a fault), and the folders
# hold nothing else: no temporary, backup or journal.
# aon_check NAME ARGS...: old outputs in aon_seed (made by the caller),
# the new ones by ARGS in aon_new; each fault in a copy of aon_seed.
aon_list() { (cd "$1" && find . -mindepth 1 | LC_ALL=C sort | tr '\n' ' '); }
aon_same() { # DIR_A DIR_B: same names, same bytes (stats.json: names only)
    [ "$(aon_list "$1")" = "$(aon_list "$2")" ] || return 1
    local f
    while read -r f; do
        case $f in *stats.json) continue ;; esac
        [ -d "$1/$f" ] || cmp -s "$1/$f" "$2/$f" || return 1
    done < <(cd "$1" && find . -mindepth 1 -type f)
    return 0
}
aon_check() {
    local name=$1 how k word reached=0
    shift
    rm -rf aon_new && cp -a aon_seed aon_new
    (cd aon_new && "$FRONTDT" "$@" >/dev/null 2>&1) || fail "$name: the run without a fault failed"
    for how in fail signal; do
        for k in $(seq 1 80); do
            rm -rf aon_run && cp -a aon_seed aon_run
            (cd aon_run && FDT_TEST_COMMIT_FAULT=$k:$how "$FRONTDT" "$@" >../aon.out 2>../aon.err)
            RC=$?
            word=$(sed -n 's/^frontdt: test fault ([a-z]*) at commit step [0-9]*: //p' aon.err)
            if [ -z "$word" ]; then
                [ "$RC" = 0 ] || fail "$name: no fault at step $k, yet exit $RC: $(head -c 300 aon.err)"
                aon_same aon_run aon_new || fail "$name: a run past every step did not write the new outputs"
                break
            fi
            reached=$((reached + 1))
            if [ "$word" = committed ]; then
                # after the commit point: all new (a signal still exits 6)
                [ "$RC" = "$([ $how = fail ] && echo 0 || echo 6)" ] ||
                    fail "$name: $how after the commit point: exit $RC"
                aon_same aon_run aon_new ||
                    fail "$name: $how after the commit point: not every output is new: $(aon_list aon_run)"
            else
                [ "$RC" = "$([ $how = fail ] && echo 5 || echo 6)" ] ||
                    fail "$name: $how at commit step $k ($word): exit $RC: $(head -c 300 aon.err)"
                aon_same aon_run aon_seed ||
                    fail "$name: $how at commit step $k ($word): not every output is the old one: $(aon_list aon_run)"
            fi
        done
    done
    # each mode reaches the backups, the journal, the renames and the commit;
    # AON_STEPS: exactly that many (a lone file: its backup, its rename and
    # the step after it, twice; no journal step)
    if [ -n "${AON_STEPS:-}" ]; then
        [ "$reached" = "$AON_STEPS" ] || fail "$name: $reached commit steps reached, not $AON_STEPS"
    else
        [ "$reached" -ge 10 ] || fail "$name: only $reached commit steps were reached"
    fi
    rm -rf aon_run aon_new aon.out aon.err
}
rm -rf aon_seed && mkdir -p aon_seed/p aon_seed/q
(cd aon_seed && "$FRONTDT" --demo 1500 -q --mode serial -o x.msh -o x.vtk -o x.mesh -o x.ele \
    -o q/polyMesh --stats-json stats.json) || fail "all-or-none: the old outputs were not written"
aon_check aon_memory --demo 1600 -q --mode serial -o x.msh -o x.vtk -o x.mesh -o x.ele \
    -o p/polyMesh -o q/polyMesh --stats-json stats.json
# streamed outputs go through the same commit; the stale .neigh beside a
# streamed TetGen set is removed with it
rm -rf aon_seed && mkdir aon_seed
(cd aon_seed && "$FRONTDT" --demo 1500 -q --mode serial -o y.vtu -o y.ele) ||
    fail "all-or-none: the old streamed outputs were not written"
aon_check aon_stream --demo 1600 -q --mode serial --stream -o y.vtu -o y.ele -o y.fdtb
# one output alone: no journal (its rename is atomic), the same all-or-none
rm -rf aon_seed && mkdir aon_seed
(cd aon_seed && "$FRONTDT" --demo 1500 -q --mode serial -o z.msh) ||
    fail "all-or-none: the old single output was not written"
AON_STEPS=6 aon_check aon_single --demo 1600 -q --mode serial -o z.msh
rm -rf aon_seed

# --stream (issue 18): the streamed mesh's set hash equals the in-memory
# run's in every mode; what a stream cannot do is refused; --memory-limit
# refuses a run over its estimate (exit 4) before it starts and lets one
# under it run; --stats shows the memory lines.
gen_points 3000 21 >st.xyz
run st_mem "$FRONTDT" st.xyz --set-hash -q
expect_rc st_mem 0
want=$(grep set-hash st_mem.out)
[ -n "$want" ] || fail "st_mem: no set-hash line"
for m in "--mode serial" "--mode shared -t 2" "--mode message -t 3"; do
    # shellcheck disable=SC2086 # the mode's words
    run st_stream "$FRONTDT" st.xyz --stream --set-hash $m
    expect_rc st_stream 0 && {
        [ "$(grep set-hash st_stream.out)" = "$want" ] ||
            fail "--stream $m: $(grep set-hash st_stream.out), in memory $want"
    }
done
run st_count "$FRONTDT" st.xyz --mode serial
run st_count_s "$FRONTDT" st.xyz --mode serial --stream
[ "$(grep '^tets:' st_count.out)" = "$(grep '^tets:' st_count_s.out)" ] ||
    fail "--stream counts $(grep '^tets:' st_count_s.out), in memory $(grep '^tets:' st_count.out)"
# streamed cells (issue 32): the same bytes as in memory, a text table and
# a CSV one, at one and three threads, with duplicates; what cannot stream
# is refused, and the kd fronts (which cannot say when a cell is whole) too
{ cat st.xyz; head -50 st.xyz; } >stv.xyz
run stv_mem "$FRONTDT" stv.xyz -q --voronoi stv_m.txt --density stv_md.txt --voronoi-format '%i %q %v %n %f %C %d %h'
expect_rc stv_mem 0
for t in 1 3; do
    run stv_s$t "$FRONTDT" stv.xyz -q --stream -t $t --voronoi stv_s$t.txt --density stv_sd$t.txt --voronoi-format '%i %q %v %n %f %C %d %h' -o stv_s$t.vtu
    expect_rc stv_s$t 0 && {
        cmp -s stv_m.txt stv_s$t.txt || fail "--stream -t $t --voronoi: not the in-memory table"
        cmp -s stv_md.txt stv_sd$t.txt || fail "--stream -t $t --density: not the in-memory table"
        [ -s stv_s$t.vtu ] || fail "--stream -t $t --voronoi: no mesh beside the cells"
    }
done
run stv_csv_m "$FRONTDT" stv.xyz -q --voronoi stv_m.csv
run stv_csv_s "$FRONTDT" stv.xyz -q --stream --voronoi stv_s.csv
cmp -s stv_m.csv stv_s.csv || fail "--stream --voronoi F.csv: not the in-memory table"
ls -a | grep -q frontdt-spool && fail "--stream --voronoi left its spool"
usage_case u_stream_vtu "polyhedra) needs the whole mesh" st.xyz --stream --voronoi st.vtu
run stv_kd "$FRONTDT" stv.xyz -q --stream --search kd --voronoi stv_kd.txt
expect_rc stv_kd 1 && expect_in stv_kd err "sweep order"
[ ! -e stv_kd.txt ] || fail "--stream --search kd --voronoi wrote its table"
usage_case u_stream_o "format tets needs the whole mesh" st.xyz --stream -o st.tets
usage_case u_stream_check "--check needs the whole mesh" st.xyz --stream --check
usage_case u_stream_hash "--hash sorts the whole mesh" st.xyz --stream --hash
[ ! -e st.tets ] || fail "--stream -o left st.tets"
usage_case u_memlimit "--memory-limit wants" st.xyz --memory-limit 12X
usage_case u_memlimit0 "--memory-limit wants" st.xyz --memory-limit 0
usage_case u_memlimit_big "--memory-limit wants" st.xyz --memory-limit 99999999999999999G
# no digits, more than 19 digits, a unit after 'i' only with K, M or G
usage_case u_memlimit_nodigit "--memory-limit wants" st.xyz --memory-limit G
usage_case u_memlimit_20 "--memory-limit wants" st.xyz --memory-limit 12345678901234567890
usage_case u_memlimit_ib "--memory-limit wants" st.xyz --memory-limit 5iB
usage_case u_memlimit_tail "--memory-limit wants" st.xyz --memory-limit 5MBx
usage_case u_threads_empty "--threads" --threads= st.xyz
# every spelling of a unit: 1024 KiB, 1 MB and 1mib are all 1 MiB
for lim in 1024KiB 1MB 1mib 1048576b; do
    run st_limit_$lim "$FRONTDT" st.xyz --memory-limit $lim
    expect_rc st_limit_$lim 4 && expect_in st_limit_$lim err "more than --memory-limit 1 MiB"
done
run st_limit "$FRONTDT" st.xyz --memory-limit 1M
expect_rc st_limit 4 && expect_in st_limit err "more than --memory-limit 1 MiB"
run st_limit_ok "$FRONTDT" st.xyz --memory-limit 2G --stream --stats
expect_rc st_limit_ok 0 && {
    expect_in st_limit_ok err "memory estimate"
    expect_in st_limit_ok err "memory peak RSS"
    expect_in st_limit_ok err "engine            sweep"
}

if [ "$FAILS" -gt 0 ]; then
    echo "$FAILS failure(s)" >&2
    exit 1
fi
echo "all CLI tests passed"
exit 0
