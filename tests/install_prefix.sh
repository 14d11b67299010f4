#!/usr/bin/env bash
# An install into a custom prefix runs without LD_LIBRARY_PATH (issue 34
# item 7). The source is configured afresh with --prefix=TMP/prefix (the
# library and the CLI only: no tests, benchmarks, Python or MPI; -O0 to
# build quickly; LIBDIR lib), installed there with meson install as a user would (no
# DESTDIR: the rpath must name where the files really are), and then, with
# LD_LIBRARY_PATH unset:
#   - PREFIX/bin/frontdt runs and prints the hash of nine points, equal to
#     the build's CLI's;
#   - libfrontdt.so and bin/frontdt carry PREFIX/LIBDIR in their RUNPATH
#     (readelf -d), and the installed frontdt.pc's Libs give it to programs;
#   - tests/cmake/main.c built with the installed `pkg-config --cflags
#     --libs frontdt` runs (its loader finds libfrontdt by that rpath) and
#     prints the CLI's tet count and hash.
# (tests/cmake_package.sh checks the installed CMake and pkg-config files
# under a DESTDIR.) Exit 77 (skipped) without pkg-config or readelf.
# usage: install_prefix.sh MESON SOURCE_ROOT FRONTDT
set -u
meson=$1 src=$2 frontdt=$3
fail() { echo "install_prefix: FAIL: $*" >&2; exit 1; }
for p in pkg-config readelf; do
    command -v "$p" >/dev/null || { echo "install_prefix: $p not installed: skipped"; exit 77; }
done
tmp=$(mktemp -d) || fail "mktemp"
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix libdir=$tmp/prefix/lib
unset LD_LIBRARY_PATH

"$meson" setup "$tmp/build" "$src" --prefix="$prefix" --libdir=lib --buildtype=debug \
    -Denable_tests=false -Denable_bench=false -Dpython=disabled -Dmpi=disabled \
    -Denable_cgal=disabled -Denable_tetgen=disabled >"$tmp/log" 2>&1 ||
    { cat "$tmp/log"; fail "meson setup --prefix=$prefix"; }
"$meson" compile -C "$tmp/build" >>"$tmp/log" 2>&1 || { cat "$tmp/log"; fail "meson compile"; }
"$meson" install -C "$tmp/build" --quiet >>"$tmp/log" 2>&1 || { cat "$tmp/log"; fail "meson install"; }

printf '%s\n' '0 0 0' '1 0 0' '0 1 0' '1 1 0' '0 0 1' '1 0 1' '0 1 1' '1 1 1' '0.5 0.5 0.5' >"$tmp/pts.xyz"
want=$("$frontdt" --quiet --hash "$tmp/pts.xyz") || fail "the build's CLI on pts.xyz"
[ -n "${want#hash: }" ] || fail "no hash from the build's CLI"

got=$("$prefix/bin/frontdt" --quiet --hash "$tmp/pts.xyz") || fail "the installed frontdt did not run"
[ "$got" = "$want" ] || fail "the installed frontdt says '$got', the build's '$want'"
echo "install_prefix: $prefix/bin/frontdt: ok ($got)"

lib=$(ls "$libdir"/libfrontdt.so.*.*.* 2>/dev/null | head -1)
[ -n "$lib" ] || fail "no libfrontdt.so.X.Y.Z in $libdir"
for f in "$lib" "$prefix/bin/frontdt"; do
    rp=$(readelf -d "$f" | sed -n 's/.*(RUNPATH).*\[\(.*\)\]/\1/p')
    tr ':' '\n' <<<"$rp" | grep -qxF "$libdir" || fail "$f: RUNPATH '$rp' lacks $libdir"
done
echo "install_prefix: RUNPATH $libdir: ok"

flags=$(PKG_CONFIG_PATH="$libdir/pkgconfig" pkg-config --cflags --libs frontdt) ||
    fail "pkg-config --cflags --libs frontdt"
grep -qF -- "-Wl,-rpath,$libdir" <<<"$flags" || fail "frontdt.pc gives no rpath: $flags"
# shellcheck disable=SC2086
"${CC:-cc}" -std=c11 -o "$tmp/user" "$src/tests/cmake/main.c" $flags ||
    fail "building with pkg-config's flags: $flags"
out=$("$tmp/user" "$tmp/pts.xyz") || fail "the program built with pkg-config did not run: $(ldd "$tmp/user" | grep frontdt)"
grep -qx 'tets: 12' <<<"$out" || fail "wrong tet count: $out"
grep -qx "$want" <<<"$out" || fail "hash differs from the CLI's ($want): $out"
echo "install_prefix: pkg-config program: ok ($(tr '\n' ' ' <<<"$out"))"
