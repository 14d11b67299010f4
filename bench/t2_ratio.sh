#!/bin/sh
# Two threads against serial on the same files, runs interleaved:
#   bench/t2_ratio.sh FRONTDT REPS FILE...
# prints, per file, the medians of frontdt's own `time triangulate` (the
# triangulation alone: no reader, no output, no hash) over REPS runs of
# `--mode serial` and of `--threads 2`, and their ratio. The bench harness
# (bench/run) is the reference for reported tables; this is the quick
# check of issue 16's two-thread target between its runs (bench/NOTES.md).
set -eu
if [ $# -lt 3 ]; then
    echo "usage: $0 FRONTDT REPS FILE..." >&2
    exit 2
fi
bin=$1
reps=$2
shift 2
tri() {
    "$bin" "$@" -q --stats 2>&1 | awk '/time triangulate/ {print $3}'
}
median() {
    sort -n | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}'
}
for f in "$@"; do
    s=$(mktemp)
    t=$(mktemp)
    i=0
    while [ "$i" -lt "$reps" ]; do
        tri "$f" --mode serial >>"$s"
        tri "$f" --threads 2 >>"$t"
        i=$((i + 1))
    done
    ms=$(median <"$s")
    mt=$(median <"$t")
    rm -f "$s" "$t"
    awk -v f="$(basename "$f")" -v s="$ms" -v t="$mt" \
        'BEGIN {printf "%s serial %s two %s ratio %.3f\n", f, s, t, s / t}'
done
