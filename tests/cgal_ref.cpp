/*
 * cgal_ref IN.xyz OUT.tets
 *
 * The reference tetrahedralization: CGAL's Delaunay_triangulation_3 with
 * exact predicates. CGAL breaks ties (cospherical, coplanar points) with
 * the symbolic perturbation of Devillers & Teillaud, ranking points
 * lexicographically by (x, y, z), so its finite cells are THE perturbed
 * Delaunay tetrahedralization: unique, independent of insertion order.
 * frontdt must reproduce it exactly; tests compare the canonical .tets
 * bytes and the FNV-1a hash printed on the SUMMARY line.
 *
 * Duplicates are merged before insertion (tests/refcommon.hpp): CGAL's
 * range insert with info would give a repeated point the info of its LAST
 * occurrence, and the contract (include/frontdt.h) is the first.
 *
 * Exit status: 0 success, 1 usage or I/O error, 3 degenerate input (fewer
 * than 4 distinct points or all coplanar: no tetrahedron exists).
 */
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <climits>
#include <cstdio>
#include <utility>
#include <vector>

#include "refcommon.hpp"

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_3<int32_t, K>;
using Cb = CGAL::Delaunay_triangulation_cell_base_3<K>;
using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb>;
using DT = CGAL::Delaunay_triangulation_3<K, Tds>;
using Point = K::Point_3;

} // namespace

int main(int argc, char **argv)
{
    if (argc != 3) {
        std::fprintf(stderr, "usage: %s IN.xyz OUT.tets\n", argv[0]);
        return 1;
    }
    const double t0 = fdt_ref::now_s();
    std::vector<double> xyz;
    if (!fdt_ref::read_points("cgal_ref", argv[1], xyz))
        return 1;
    const size_t n = xyz.size() / 3;
    const double t1 = fdt_ref::now_s();

    std::vector<int32_t> map, firsts;
    fdt_ref::merge_duplicates(xyz, map, firsts);
    std::vector<std::pair<Point, int32_t>> pts;
    pts.reserve(firsts.size());
    for (int32_t i : firsts) {
        const double *c = &xyz[3 * (size_t)i];
        pts.emplace_back(Point(c[0], c[1], c[2]), i);
    }
    DT dt;
    // The range insert spatially sorts, then inserts each point with its
    // info: the vertex's info is the point's first input index.
    dt.insert(pts.begin(), pts.end());
    if (dt.dimension() < 3) {
        std::fprintf(stderr,
                     "cgal_ref: %s: degenerate input (%zu distinct points, "
                     "dimension %d): no tetrahedra\n",
                     argv[1], firsts.size(), dt.dimension());
        return 3;
    }
    std::vector<fdt_ref::tet4> tets;
    tets.reserve(dt.number_of_finite_cells());
    for (auto c : dt.finite_cell_handles())
        tets.push_back({c->vertex(0)->info(), c->vertex(1)->info(),
                        c->vertex(2)->info(), c->vertex(3)->info()});
    const double t2 = fdt_ref::now_s();

    fdt_ref::canonicalize(tets);
    uint64_t hash = 0;
    std::string err;
    if (!fdt_ref::write_tets(argv[2], tets, &hash, err)) {
        std::fprintf(stderr, "cgal_ref: %s\n", err.c_str());
        return 1;
    }
    const double t3 = fdt_ref::now_s();
    fdt_ref::print_summary("cgal", n, tets.size(), t1 - t0, t2 - t1, t3 - t0,
                           hash);
    return 0;
}
