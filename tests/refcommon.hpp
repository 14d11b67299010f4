/*
 * Shared helpers for the reference triangulators (tests/cgal_ref.cpp,
 * tests/tetgen_ref.cpp) and the benchmark harness. C++17, header only.
 *
 * What lives here is exactly what must agree bit for bit with frontdt so
 * that outputs can be compared byte by byte:
 *   - the .xyz reader (correctly rounded decimal -> double, like strtod);
 *   - duplicate merging: bit-identical coordinates, -0 equal to +0, merged
 *     into the FIRST input index (include/frontdt.h, fdt_triangulate);
 *   - the canonical .tets text and its FNV-1a 64 hash (fdt_result_hash).
 * Plus peak-RSS and monotonic-clock helpers for the SUMMARY lines.
 *
 * Every function reports failure through its return value and an error
 * string; nothing here prints or exits.
 */
#ifndef FDT_TESTS_REFCOMMON_HPP
#define FDT_TESTS_REFCOMMON_HPP

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <system_error>
#include <vector>

#include <sys/resource.h>
#include <time.h>

namespace fdt_ref {

/* ---------------------------------------------------------------- timing */

/* Seconds on CLOCK_MONOTONIC: immune to wall-clock steps during a run. */
inline double now_s()
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Peak resident set size of this process in KiB (Linux reports ru_maxrss
 * in KiB). 0 if getrusage fails. */
inline long peak_rss_kb()
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0)
        return 0;
    return ru.ru_maxrss;
}

/* ---------------------------------------------------------------- reader */

namespace detail {

inline bool is_sep(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == ',' || c == '\v' ||
           c == '\f';
}

} // namespace detail

/*
 * Reads an .xyz file: one point per line, x y z separated by whitespace
 * and/or commas, '#' starts a comment running to the end of the line,
 * blank lines are skipped. Any other line must hold exactly 3 finite
 * numbers. The whole file is read with one fread and parsed in place with
 * std::from_chars, which rounds correctly (the same doubles strtod gives,
 * without its locale dependence).
 * On success xyz holds 3n doubles and the function returns true; otherwise
 * err says "path:line: what" and xyz is empty.
 */
inline bool read_xyz(const char *path, std::vector<double> &xyz,
                     std::string &err)
{
    xyz.clear();
    FILE *f = std::fopen(path, "rb");
    if (!f) {
        err = std::string(path) + ": " + std::strerror(errno);
        return false;
    }
    std::vector<char> buf;
    {
        char chunk[1 << 16];
        size_t got;
        while ((got = std::fread(chunk, 1, sizeof chunk, f)) > 0)
            buf.insert(buf.end(), chunk, chunk + got);
        bool bad = std::ferror(f) != 0;
        std::fclose(f);
        if (bad) {
            err = std::string(path) + ": read error";
            return false;
        }
    }
    // A rough guess of the point count (about 30 bytes a line) avoids most
    // regrowth of xyz on big files.
    xyz.reserve(buf.size() / 10 + 3);
    const char *p = buf.data();
    const char *end = p + buf.size();
    size_t line = 0;
    while (p < end) {
        ++line;
        const char *eol = static_cast<const char *>(
            std::memchr(p, '\n', (size_t)(end - p)));
        if (!eol)
            eol = end;
        double v[3];
        int k = 0;
        const char *q = p;
        for (;;) {
            while (q < eol && detail::is_sep(*q))
                ++q;
            if (q == eol || *q == '#')
                break;
            double d;
            // from_chars does not accept a leading '+'; the C reader does.
            const char *s = q;
            if (*s == '+' && s + 1 < eol && *(s + 1) != '-')
                ++s;
            auto r = std::from_chars(s, eol, d, std::chars_format::general);
            if (r.ec == std::errc::result_out_of_range) {
                // libstdc++ also says out of range for subnormal and
                // underflowing values, which strtod returns as finite
                // doubles: re-read the token with strtod, keep it if finite.
                char tok[128];
                size_t len = (size_t)(r.ptr - s);
                if (len < sizeof tok) {
                    std::memcpy(tok, s, len);
                    tok[len] = '\0';
                    d = std::strtod(tok, nullptr);
                    if (std::isfinite(d))
                        r.ec = std::errc();
                }
            }
            if (r.ec == std::errc::result_out_of_range) {
                err = std::string(path) + ":" + std::to_string(line) +
                      ": number out of double range";
                xyz.clear();
                return false;
            }
            if (r.ec != std::errc() ||
                (r.ptr < eol && !detail::is_sep(*r.ptr) && *r.ptr != '#')) {
                err = std::string(path) + ":" + std::to_string(line) +
                      ": not a number";
                xyz.clear();
                return false;
            }
            if (!std::isfinite(d)) {
                err = std::string(path) + ":" + std::to_string(line) +
                      ": NaN or infinite coordinate";
                xyz.clear();
                return false;
            }
            if (k == 3) {
                err = std::string(path) + ":" + std::to_string(line) +
                      ": more than 3 numbers";
                xyz.clear();
                return false;
            }
            v[k++] = d;
            q = r.ptr;
        }
        if (k != 0 && k != 3) {
            err = std::string(path) + ":" + std::to_string(line) +
                  ": expected 3 numbers, found " + std::to_string(k);
            xyz.clear();
            return false;
        }
        if (k == 3)
            xyz.insert(xyz.end(), v, v + 3);
        p = eol + 1;
    }
    return true;
}

/* read_xyz for a program called `name`: prints "name: error" and returns
 * false on failure, or when the file has more points than int32 ids. */
inline bool read_points(const char *name, const char *path,
                        std::vector<double> &xyz)
{
    std::string err;
    if (!read_xyz(path, xyz, err)) {
        std::fprintf(stderr, "%s: %s\n", name, err.c_str());
        return false;
    }
    if (xyz.size() / 3 > (size_t)INT32_MAX) {
        std::fprintf(stderr, "%s: %zu points: more than int32 ids\n", name,
                     xyz.size() / 3);
        return false;
    }
    return true;
}

/* ------------------------------------------------------ duplicate merging */

/*
 * Maps every point to the first input index with the same coordinates
 * (bit-identical after turning -0 into +0: they are the same point).
 * map[i] == i for the first of its coordinates. firsts lists those first
 * indices in ascending order: the distinct points to triangulate.
 * Open addressing on a table of at least twice the point count keeps it
 * linear time; a hash collision only costs a probe, equality is exact.
 */
inline void merge_duplicates(const std::vector<double> &xyz,
                             std::vector<int32_t> &map,
                             std::vector<int32_t> &firsts)
{
    const size_t n = xyz.size() / 3;
    map.assign(n, 0);
    firsts.clear();
    auto key = [&](size_t i, int c) {
        double d = xyz[3 * i + (size_t)c] + 0.0; // -0 + 0 == +0 (round to nearest)
        uint64_t b;
        std::memcpy(&b, &d, sizeof b);
        return b;
    };
    size_t cap = 16;
    while (cap < 2 * n)
        cap <<= 1;
    std::vector<int32_t> table(cap, -1);
    for (size_t i = 0; i < n; ++i) {
        uint64_t kx = key(i, 0), ky = key(i, 1), kz = key(i, 2);
        // A 64-bit mix of the three words (splitmix64 finaliser).
        uint64_t h = kx * 0x9e3779b97f4a7c15ULL ^ (ky + 0x632be59bd9b4e019ULL) *
                     0xbf58476d1ce4e5b9ULL ^ kz * 0x94d049bb133111ebULL;
        h ^= h >> 31;
        h *= 0xd6e8feb86659fd93ULL;
        h ^= h >> 32;
        size_t s = (size_t)h & (cap - 1);
        for (;;) {
            int32_t j = table[s];
            if (j < 0) {
                table[s] = (int32_t)i;
                map[i] = (int32_t)i;
                firsts.push_back((int32_t)i);
                break;
            }
            if (key((size_t)j, 0) == kx && key((size_t)j, 1) == ky &&
                key((size_t)j, 2) == kz) {
                map[i] = j;
                break;
            }
            s = (s + 1) & (cap - 1);
        }
    }
}

/* ------------------------------------------------------- canonical output */

using tet4 = std::array<int32_t, 4>;

/* Sorts each tet's ids ascending, then the tets as integer tuples. */
inline void canonicalize(std::vector<tet4> &tets)
{
    for (tet4 &t : tets)
        std::sort(t.begin(), t.end());
    std::sort(tets.begin(), tets.end());
}

/* FNV-1a 64 over bytes, continuing from h (start with fnv_basis). */
constexpr uint64_t fnv_basis = 14695981039346656037ULL;
constexpr uint64_t fnv_prime = 1099511628211ULL;

inline uint64_t fnv1a(uint64_t h, const char *bytes, size_t len)
{
    for (size_t i = 0; i < len; ++i) {
        h ^= (unsigned char)bytes[i];
        h *= fnv_prime;
    }
    return h;
}

namespace detail {

/* Appends the decimal digits of v (v >= 0) to out; returns the new end. */
inline char *put_uint(char *out, uint32_t v)
{
    char tmp[12];
    int k = 0;
    do {
        tmp[k++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    while (k)
        *out++ = tmp[--k];
    return out;
}

} // namespace detail

/*
 * Writes the canonical text of already canonical tets (canonicalize) to
 * path ("a b c d\n" per tet) and returns its FNV-1a 64 hash in *hash: the
 * value frontdt's `--hash` and fdt_result_hash() give for the same set.
 * path may be NULL to hash only. The text is produced in 1 MiB blocks so
 * that writing and hashing never hold the whole file in memory.
 */
inline bool write_tets(const char *path, const std::vector<tet4> &tets,
                       uint64_t *hash, std::string &err)
{
    FILE *f = nullptr;
    if (path) {
        f = std::fopen(path, "wb");
        if (!f) {
            err = std::string(path) + ": " + std::strerror(errno);
            return false;
        }
    }
    uint64_t h = fnv_basis;
    std::vector<char> buf(1 << 20);
    char *w = buf.data();
    char *lim = buf.data() + buf.size() - 64; // one line is at most 4*11 bytes
    bool ok = true;
    auto flush = [&]() {
        size_t len = (size_t)(w - buf.data());
        h = fnv1a(h, buf.data(), len);
        if (f && std::fwrite(buf.data(), 1, len, f) != len)
            ok = false;
        w = buf.data();
    };
    for (const tet4 &t : tets) {
        for (int c = 0; c < 4; ++c) {
            w = detail::put_uint(w, (uint32_t)t[(size_t)c]);
            *w++ = c == 3 ? '\n' : ' ';
        }
        if (w >= lim)
            flush();
    }
    flush();
    if (f && std::fclose(f) != 0)
        ok = false;
    if (!ok) {
        err = std::string(path) + ": write failed";
        return false;
    }
    *hash = h;
    return true;
}

/* The SUMMARY line every reference prints (liburcu-style, one line,
 * key=value, machine-readable by the bench harness and tests). */
inline void print_summary(const char *code, size_t points, size_t tets,
                          double read_s, double tri_s, double total_s,
                          uint64_t hash)
{
    std::printf("SUMMARY code=%s points=%zu tets=%zu read_s=%.6f tri_s=%.6f "
                "total_s=%.6f peak_rss_kb=%ld hash=%016llx\n",
                code, points, tets, read_s, tri_s, total_s, peak_rss_kb(),
                (unsigned long long)hash);
    std::fflush(stdout);
}

} // namespace fdt_ref

#endif
