/*
 * tetgen_ref IN.xyz OUT.tets
 *
 * A second, independent reference: TetGen 1.5 (libtet) computing the
 * Delaunay tetrahedralization of the point set (no -p: no facets, so it
 * meshes the convex hull; no -q/-a: no refinement, so no Steiner points).
 * TetGen breaks cospherical ties differently from CGAL (its perturbation
 * is not the lexicographic one), so the tests compare it with frontdt only
 * on random, non-degenerate inputs, where the Delaunay mesh is unique.
 *
 * Duplicates are merged first (tests/refcommon.hpp) so every output id is
 * the first input index of its coordinates, like frontdt and cgal_ref.
 *
 * Exit status: 0 success, 1 usage or I/O error, 2 TetGen failed, 3 fewer
 * than 4 distinct points.
 */
#define TETLIBRARY
#include <tetgen.h>

#include <climits>
#include <cstdio>
#include <vector>

#include "refcommon.hpp"

int main(int argc, char **argv)
{
    if (argc != 3) {
        std::fprintf(stderr, "usage: %s IN.xyz OUT.tets\n", argv[0]);
        return 1;
    }
    const double t0 = fdt_ref::now_s();
    std::vector<double> xyz;
    if (!fdt_ref::read_points("tetgen_ref", argv[1], xyz))
        return 1;
    const size_t n = xyz.size() / 3;
    const double t1 = fdt_ref::now_s();

    std::vector<int32_t> map, firsts;
    fdt_ref::merge_duplicates(xyz, map, firsts);
    if (firsts.size() < 4) {
        std::fprintf(stderr, "tetgen_ref: %s: only %zu distinct points\n",
                     argv[1], firsts.size());
        return 3;
    }
    tetgenio in, out;
    in.firstnumber = 0;
    in.numberofpoints = (int)firsts.size();
    // tetgenio's destructor frees pointlist with delete[].
    in.pointlist = new REAL[3 * firsts.size()];
    for (size_t k = 0; k < firsts.size(); ++k)
        for (int c = 0; c < 3; ++c)
            in.pointlist[3 * k + (size_t)c] = xyz[3 * (size_t)firsts[k] + (size_t)c];
    // Q: quiet. z: number output from 0. No other switch: plain Delaunay
    // tetrahedralization of the points (the convex hull is filled).
    char switches[] = "Qz";
    try {
        tetrahedralize(switches, &in, &out);
    } catch (int code) {
        std::fprintf(stderr, "tetgen_ref: %s: TetGen failed with code %d\n",
                     argv[1], code);
        return 2;
    }
    if (out.numberofpoints != in.numberofpoints || out.numberofcorners != 4) {
        // Steiner points or second-order elements would make the ids
        // meaningless; the switches above must never produce them.
        std::fprintf(stderr, "tetgen_ref: unexpected output: %d points for "
                     "%d input, %d corners\n", out.numberofpoints,
                     in.numberofpoints, out.numberofcorners);
        return 2;
    }
    std::vector<fdt_ref::tet4> tets((size_t)out.numberoftetrahedra);
    for (size_t t = 0; t < tets.size(); ++t)
        for (size_t c = 0; c < 4; ++c) {
            int id = out.tetrahedronlist[4 * t + c];
            if (id < 0 || id >= in.numberofpoints) {
                std::fprintf(stderr, "tetgen_ref: vertex id %d out of range\n",
                             id);
                return 2;
            }
            tets[t][c] = firsts[(size_t)id];
        }
    const double t2 = fdt_ref::now_s();

    fdt_ref::canonicalize(tets);
    uint64_t hash = 0;
    std::string err;
    if (!fdt_ref::write_tets(argv[2], tets, &hash, err)) {
        std::fprintf(stderr, "tetgen_ref: %s\n", err.c_str());
        return 1;
    }
    const double t3 = fdt_ref::now_s();
    fdt_ref::print_summary("tetgen", n, tets.size(), t1 - t0, t2 - t1,
                           t3 - t0, hash);
    return 0;
}
