/*
 * cgal_periodic IN.xyz LO L OUT.tets
 *
 * The reference periodic tetrahedralization (issue 33): CGAL's
 * Periodic_3_Delaunay_triangulation_3 of the points of IN.xyz (x y z a
 * line, distinct, every coordinate in [LO, LO + L)) in the cube of side L
 * at LO, periodic along x, y and z, with exact predicates on the
 * translated points and CGAL's symbolic perturbation. Its tets (each
 * once, UNIQUE) go to OUT.tets as frontdt writes them with --periodic xyz:
 * the 4 input indices ascending, then the 4 image offsets relative to the
 * first, lines sorted.
 *
 * cgal_periodic IN.xyz LO L --time: the points inserted as one range (CGAL's
 * spatial sort, no indices), and "cells N seconds S" printed: for the
 * speed comparison of bench/NOTES.md entry 108.
 *
 * Exit status: 0 success, 1 usage or I/O error, 3 when CGAL's
 * triangulation is not in one sheet (too few points for the cube).
 */
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Periodic_3_Delaunay_triangulation_3.h>
#include <CGAL/Periodic_3_Delaunay_triangulation_traits_3.h>
#include <CGAL/Periodic_3_triangulation_ds_cell_base_3.h>
#include <CGAL/Periodic_3_triangulation_ds_vertex_base_3.h>
#include <CGAL/Triangulation_data_structure_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <utility>
#include <vector>

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Gt = CGAL::Periodic_3_Delaunay_triangulation_traits_3<K>;
using VbDS = CGAL::Periodic_3_triangulation_ds_vertex_base_3<>;
using Vb = CGAL::Triangulation_vertex_base_3<Gt, VbDS>;
using VbI = CGAL::Triangulation_vertex_base_with_info_3<unsigned, Gt, Vb>;
using CbDS = CGAL::Periodic_3_triangulation_ds_cell_base_3<>;
using Cb = CGAL::Triangulation_cell_base_3<Gt, CbDS>;
using Tds = CGAL::Triangulation_data_structure_3<VbI, Cb>;
using P3DT3 = CGAL::Periodic_3_Delaunay_triangulation_3<Gt, Tds>;

struct Vert {
    unsigned id;
    int off[3];
    bool operator<(const Vert &o) const
    {
        if (id != o.id)
            return id < o.id;
        for (int k = 0; k < 3; k++)
            if (off[k] != o.off[k])
                return off[k] < o.off[k];
        return false;
    }
};

} // namespace

int main(int argc, char **argv)
{
    if (argc != 5) {
        std::fprintf(stderr, "usage: cgal_periodic IN.xyz LO L OUT.tets\n");
        return 1;
    }
    const double lo = std::strtod(argv[2], nullptr), len = std::strtod(argv[3], nullptr);
    std::FILE *in = std::fopen(argv[1], "r");
    if (!in) {
        std::perror(argv[1]);
        return 1;
    }
    std::vector<P3DT3::Point> pts;
    double x, y, z;
    while (std::fscanf(in, "%lf %lf %lf", &x, &y, &z) == 3)
        pts.emplace_back(x, y, z);
    std::fclose(in);
    P3DT3 T(P3DT3::Iso_cuboid(lo, lo, lo, lo + len, lo + len, lo + len));
    if (std::string(argv[4]) == "--time") {
        auto t0 = std::chrono::steady_clock::now();
        T.insert(pts.begin(), pts.end(), true);
        if (!T.is_1_cover() && T.is_triangulation_in_1_sheet())
            T.convert_to_1_sheeted_covering();
        double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf("cells %zu seconds %.3f\n", (size_t)T.number_of_cells(), s);
        return T.is_1_cover() ? 0 : 3;
    }
    /* one at a time, each vertex given its input index (the points are
     * distinct; the perturbed triangulation is unique, so the order does
     * not matter) */
    for (unsigned i = 0; i < pts.size(); i++)
        T.insert(pts[i])->info() = i;
    if (!T.is_triangulation_in_1_sheet()) {
        std::fprintf(stderr, "cgal_periodic: not in one sheet\n");
        return 3;
    }
    /* a set that stayed in the 27-sheeted covering while it was built
     * (clusters leave empty regions wider than the box allows) */
    if (!T.is_1_cover())
        T.convert_to_1_sheeted_covering();
    std::vector<std::array<Vert, 4>> rows;
    for (auto c = T.cells_begin(); c != T.cells_end(); ++c) {
        std::array<Vert, 4> r;
        for (int i = 0; i < 4; i++) {
            P3DT3::Offset o = T.get_offset(c, i);
            r[i].id = c->vertex(i)->info();
            for (int k = 0; k < 3; k++)
                r[i].off[k] = o[k];
        }
        const Vert low = *std::min_element(r.begin(), r.end());
        for (auto &v : r)
            for (int k = 0; k < 3; k++)
                v.off[k] -= low.off[k];
        std::sort(r.begin(), r.end());
        rows.push_back(r);
    }
    std::sort(rows.begin(), rows.end());
    std::FILE *out = std::fopen(argv[4], "w");
    if (!out) {
        std::perror(argv[4]);
        return 1;
    }
    for (const auto &r : rows) {
        std::fprintf(out, "%u %u %u %u", r[0].id, r[1].id, r[2].id, r[3].id);
        for (const auto &v : r)
            std::fprintf(out, " %d %d %d", v.off[0], v.off[1], v.off[2]);
        std::fputc('\n', out);
    }
    return std::fclose(out) == 0 ? 0 : 1;
}
