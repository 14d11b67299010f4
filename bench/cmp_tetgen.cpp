/*
 * cmp_tetgen IN.xyz [OUT.tets]
 *
 * TetGen 1.5 (libtet) as a benchmark peer: the Delaunay tetrahedralization
 * of the points (switches "Qz": quiet, 0-based; no -p, -q, -a: no facets,
 * no refinement, no Steiner points), the computation of
 * tests/tetgen_ref.cpp. TetGen is sequential: --threads other than 0 or 1
 * is refused with exit 4 (not available). Its tie-breaking on cospherical
 * points is not CGAL's, so bench/run expects its hash to equal the others
 * only on inputs in general position.
 *
 * Times, SUMMARY line and exit codes: bench/cmpcommon.hpp.
 */
#define TETLIBRARY
#include <tetgen.h>

#include <memory>
#include <vector>

#include "cmpcommon.hpp"

int main(int argc, char **argv)
{
    fdt_bench::args a;
    if (!fdt_bench::parse_args(argc, argv, "cmp_tetgen", a))
        return fdt_bench::EXIT_USAGE;
    if (a.threads > 1) {
        std::fprintf(stderr, "cmp_tetgen: TetGen is sequential: %d threads "
                     "not available\n", a.threads);
        return fdt_bench::EXIT_UNAVAILABLE;
    }
    const double t0 = fdt_ref::now_s();
    fdt_bench::input in;
    if (!fdt_bench::read_input("cmp_tetgen", a.input, in))
        return fdt_bench::EXIT_USAGE;
    const double t1 = fdt_ref::now_s();

    fdt_ref::merge_duplicates(in.xyz, in.map, in.firsts);
    const std::vector<int32_t> &firsts = in.firsts;
    if (firsts.size() < 4) {
        std::fprintf(stderr, "cmp_tetgen: %s: only %zu distinct points\n",
                     a.input, firsts.size());
        return fdt_bench::EXIT_DEGENERATE;
    }
    // Heap-allocated and freed after the SUMMARY line, like frontdt's
    // result: outside tri_s, inside bench/run's wall_s.
    auto tin = std::make_unique<tetgenio>();
    auto tout = std::make_unique<tetgenio>();
    tin->firstnumber = 0;
    tin->numberofpoints = (int)firsts.size();
    // tetgenio's destructor frees pointlist with delete[].
    tin->pointlist = new REAL[3 * firsts.size()];
    for (size_t k = 0; k < firsts.size(); ++k)
        for (int c = 0; c < 3; ++c)
            tin->pointlist[3 * k + (size_t)c] =
                in.xyz[3 * (size_t)firsts[k] + (size_t)c];
    char switches[] = "Qz";
    try {
        tetrahedralize(switches, tin.get(), tout.get());
    } catch (int code) {
        // TetGen reports every failure, coplanar input included, by
        // throwing an int.
        std::fprintf(stderr, "cmp_tetgen: %s: TetGen failed with code %d\n",
                     a.input, code);
        return fdt_bench::EXIT_LIBRARY;
    }
    if (tout->numberofpoints != tin->numberofpoints ||
        tout->numberofcorners != 4) {
        std::fprintf(stderr, "cmp_tetgen: unexpected output: %d points for "
                     "%d input, %d corners\n", tout->numberofpoints,
                     tin->numberofpoints, tout->numberofcorners);
        return fdt_bench::EXIT_LIBRARY;
    }
    std::vector<fdt_ref::tet4> tets((size_t)tout->numberoftetrahedra);
    for (size_t t = 0; t < tets.size(); ++t)
        for (size_t c = 0; c < 4; ++c) {
            int id = tout->tetrahedronlist[4 * t + c];
            if (id < 0 || id >= tin->numberofpoints) {
                std::fprintf(stderr, "cmp_tetgen: vertex id %d out of range\n",
                             id);
                return fdt_bench::EXIT_LIBRARY;
            }
            tets[t][c] = firsts[(size_t)id];
        }
    const double t2 = fdt_ref::now_s();

    uint64_t hash = 0;
    if (!fdt_bench::finish_tets("cmp_tetgen", a.output, tets, &hash))
        return fdt_bench::EXIT_USAGE;
    const double t3 = fdt_ref::now_s();
    fdt_bench::print_summary("tetgen", 1, in.n, firsts.size(), tets.size(),
                             t1 - t0, t2 - t1, t3 - t2, t3 - t0, hash);
    return fdt_bench::EXIT_OK;
}
