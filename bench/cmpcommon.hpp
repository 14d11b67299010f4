/*
 * What the benchmark comparators (bench/cmp_*.cpp) share, on top of
 * tests/refcommon.hpp (reader, duplicate merge, canonical hash, timing):
 * the command line, the phases each one times, and its SUMMARY line.
 *
 * Every comparator runs
 *     cmp_X [--threads N] IN.xyz [OUT.tets]
 * and prints one line on stdout (liburcu's SUMMARY idea, read by bench/run):
 *     SUMMARY code=X threads=N points=.. vertices=.. tets=.. read_s=..
 *             tri_s=.. hash_s=.. total_s=.. peak_rss_kb=.. hash=..
 * It is the line of tests/cgal_ref.cpp with three keys more (threads,
 * vertices, hash_s); every key is key=value, so readers of the shorter
 * line read this one too.
 *
 * What each time covers, on CLOCK_MONOTONIC (the same phases frontdt's
 * --stats-json reports as t_read and t_triangulate):
 *   read_s   the .xyz file to an array of doubles;
 *   tri_s    that array to the tets as 4 first-input indices each: the
 *            duplicate merge, building the library's own input, the
 *            triangulation itself and reading its tets back out;
 *   hash_s   the canonical sort and FNV-1a hash (and writing OUT.tets when
 *            asked): checking, not triangulating, so kept apart;
 *   total_s  from the start of main to the SUMMARY line (read + tri + hash).
 * Process start and exit (freeing the triangulation included) are outside
 * all of them; bench/run measures the whole process as wall_s.
 * peak_rss_kb is this process's peak resident set (getrusage) when the line
 * is printed.
 *
 * Exit status: 0 success, 1 usage or I/O error, 2 the library failed,
 * 3 fewer than 4 distinct points or no 3-D extent, 4 not available in this
 * build (e.g. --threads without TBB): bench/run records 4 as
 * 'unavailable'.
 */
#ifndef FDT_BENCH_CMPCOMMON_HPP
#define FDT_BENCH_CMPCOMMON_HPP

#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "refcommon.hpp"

namespace fdt_bench {

enum exit_code {
    EXIT_OK = 0,
    EXIT_USAGE = 1,
    EXIT_LIBRARY = 2,
    EXIT_DEGENERATE = 3,
    EXIT_UNAVAILABLE = 4
};

struct args {
    const char *input = nullptr;
    const char *output = nullptr; // NULL: hash only
    int threads = 0;              // 0: the comparator's sequential code
};

/* Parses [--threads N] IN.xyz [OUT.tets]; false on a usage error (after
 * printing the usage line to stderr: this is a program, not the library). */
inline bool parse_args(int argc, char **argv, const char *name, args &a)
{
    int pos = 0;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--threads") || !std::strcmp(argv[i], "-t")) {
            if (i + 1 >= argc)
                goto bad;
            char *end;
            long t = std::strtol(argv[++i], &end, 10);
            if (*end || end == argv[i] || t < 0 || t > 4096)
                goto bad;
            a.threads = (int)t;
        } else if (argv[i][0] == '-' && argv[i][1] != '\0') {
            goto bad;
        } else if (pos == 0) {
            a.input = argv[i];
            ++pos;
        } else if (pos == 1) {
            a.output = argv[i];
            ++pos;
        } else {
            goto bad;
        }
    }
    if (a.input)
        return true;
bad:
    std::fprintf(stderr, "usage: %s [--threads N] IN.xyz [OUT.tets]\n", name);
    return false;
}

/* The points of one run: the file's doubles, and the first input index of
 * every distinct point (the ids all outputs use, like frontdt's). */
struct input {
    std::vector<double> xyz;
    std::vector<int32_t> map, firsts;
    size_t n = 0;
};

/* Reads IN.xyz into in.xyz; prints the error and returns false on failure. */
inline bool read_input(const char *name, const char *path, input &in)
{
    if (!fdt_ref::read_points(name, path, in.xyz))
        return false;
    in.n = in.xyz.size() / 3;
    return true;
}

/* Canonicalises tets, hashes them (and writes them when output is set);
 * prints the error and returns false on failure. */
inline bool finish_tets(const char *name, const char *output,
                        std::vector<fdt_ref::tet4> &tets, uint64_t *hash)
{
    std::string err;
    fdt_ref::canonicalize(tets);
    if (!fdt_ref::write_tets(output, tets, hash, err)) {
        std::fprintf(stderr, "%s: %s\n", name, err.c_str());
        return false;
    }
    return true;
}

inline void print_summary(const char *code, int threads, size_t points,
                          size_t vertices, size_t tets, double read_s,
                          double tri_s, double hash_s, double total_s,
                          uint64_t hash)
{
    std::printf("SUMMARY code=%s threads=%d points=%zu vertices=%zu tets=%zu "
                "read_s=%.6f tri_s=%.6f hash_s=%.6f total_s=%.6f "
                "peak_rss_kb=%ld hash=%016llx\n",
                code, threads, points, vertices, tets, read_s, tri_s, hash_s,
                total_s, fdt_ref::peak_rss_kb(), (unsigned long long)hash);
    std::fflush(stdout);
}

} // namespace fdt_bench

#endif
