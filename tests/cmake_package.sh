#!/usr/bin/env bash
# Installs the build into a temporary DESTDIR (meson install --destdir) and
# builds tests/cmake/ against it twice, as a user would: with CMake's
# find_package(frontdt) (the imported target frontdt::frontdt of
# LIBDIR/cmake/frontdt/frontdtConfig.cmake) and with pkg-config
# (LIBDIR/pkgconfig/frontdt.pc). Each program triangulates a small point
# set; its tet count and canonical hash must equal the CLI's on the same
# file. Exit 77 (skipped) without cmake and pkg-config, 1 on any failure.
# Usage: cmake_package.sh MESON BUILD_ROOT PREFIX LIBDIR SOURCE_DIR FRONTDT
set -u
meson=$1 build=$2 prefix=$3 libdir=$4 src=$5 frontdt=$6
fail() { echo "cmake_package: FAIL: $*" >&2; exit 1; }
have_cmake=1 have_pc=1
command -v cmake >/dev/null || have_cmake=0
command -v pkg-config >/dev/null || have_pc=0
if ((!have_cmake && !have_pc)); then
    echo "cmake_package: neither cmake nor pkg-config installed: skipped"; exit 77
fi
tmp=$(mktemp -d) || fail "mktemp"
trap 'rm -rf "$tmp"' EXIT
dest=$tmp/dest
"$meson" install -C "$build" --destdir "$dest" --no-rebuild --quiet >"$tmp/install.log" 2>&1 ||
    { cat "$tmp/install.log"; fail "meson install --destdir"; }
case $libdir in /*) ;; *) libdir=$prefix/$libdir ;; esac
root=$dest$prefix
[ -f "$dest$libdir/cmake/frontdt/frontdtConfig.cmake" ] || fail "no frontdtConfig.cmake installed"
[ -f "$dest$libdir/cmake/frontdt/frontdtConfigVersion.cmake" ] || fail "no frontdtConfigVersion.cmake installed"
[ -f "$dest$libdir/pkgconfig/frontdt.pc" ] || fail "no frontdt.pc installed"

# Nine points: the unit cube's corners and its centre (12 tets).
printf '%s\n' '0 0 0' '1 0 0' '0 1 0' '1 1 0' '0 0 1' '1 0 1' '0 1 1' '1 1 1' '0.5 0.5 0.5' >"$tmp/pts.xyz"
want=$("$frontdt" --quiet --hash "$tmp/pts.xyz") || fail "the CLI on pts.xyz"
want_hash=${want#hash: }
[ -n "$want_hash" ] || fail "no hash from the CLI"

check_run() { # $1: label, $2: program
    out=$(LD_LIBRARY_PATH="$dest$libdir" "$2" "$tmp/pts.xyz") || fail "$1: the program failed"
    grep -qx 'tets: 12' <<<"$out" || fail "$1: wrong tet count: $out"
    grep -qx "hash: $want_hash" <<<"$out" || fail "$1: hash differs from the CLI's ($want_hash): $out"
    echo "cmake_package: $1: ok ($(tr '\n' ' ' <<<"$out"))"
}

if ((have_cmake)); then
    cmake -S "$src" -B "$tmp/cm" -DCMAKE_PREFIX_PATH="$root" -DCMAKE_BUILD_TYPE=Release \
        >"$tmp/cmake.log" 2>&1 || { cat "$tmp/cmake.log"; fail "cmake configure (find_package)"; }
    cmake --build "$tmp/cm" >>"$tmp/cmake.log" 2>&1 || { cat "$tmp/cmake.log"; fail "cmake build"; }
    check_run "cmake find_package" "$tmp/cm/user"
    # The version file: an older API (0.0) is refused, the right one found.
    mkdir -p "$tmp/ver"
    printf '%s\n' 'cmake_minimum_required(VERSION 3.13)' 'project(v C)' \
        'find_package(frontdt 0.0 EXACT QUIET)' \
        'if(frontdt_FOUND)' '  message(FATAL_ERROR "0.0 EXACT accepted")' 'endif()' \
        >"$tmp/ver/CMakeLists.txt"
    cmake -S "$tmp/ver" -B "$tmp/ver/b" -DCMAKE_PREFIX_PATH="$root" >>"$tmp/cmake.log" 2>&1 ||
        { cat "$tmp/cmake.log"; fail "frontdtConfigVersion.cmake accepted version 0.0"; }
else
    echo "cmake_package: cmake not installed: find_package part skipped"
fi

if ((have_pc)); then
    cc=${CC:-cc}
    # The installed .pc first; its private requirements (gmp, hwloc) from
    # the system. SYSROOT puts DESTDIR before the .pc file's absolute paths.
    flags=$(PKG_CONFIG_PATH="$dest$libdir/pkgconfig" PKG_CONFIG_SYSROOT_DIR="$dest" \
        pkg-config --cflags --libs frontdt) || fail "pkg-config --cflags --libs frontdt"
    # shellcheck disable=SC2086
    "$cc" -std=c11 -o "$tmp/user_pc" "$src/main.c" $flags || fail "building with pkg-config's flags: $flags"
    check_run "pkg-config" "$tmp/user_pc"
else
    echo "cmake_package: pkg-config not installed: pkg-config part skipped"
fi
