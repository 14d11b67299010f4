/*
 * cmp_cgal [--threads N] IN.xyz [OUT.tets]
 *
 * CGAL's Delaunay_triangulation_3 (exact predicates, inexact
 * constructions) as a benchmark peer. Without --threads (or with 0): the
 * sequential triangulation, code "cgal", the same computation as
 * tests/cgal_ref.cpp. With --threads N >= 1: the parallel one (Parallel_tag
 * data structure, TBB), code "cgal_par", with TBB limited to exactly N
 * threads and the lock grid sized to the points' bounding box, as CGAL's
 * documentation asks. Both give THE perturbed Delaunay tetrahedralization
 * (CGAL's symbolic perturbation breaks ties whatever the insertion order),
 * so their hash must equal frontdt's on every input.
 *
 * Times, SUMMARY line and exit codes: bench/cmpcommon.hpp. Exit 4 when
 * --threads N >= 1 is asked of a build without TBB.
 */
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/global_control.h>
#endif

#include <algorithm>
#include <memory>
#include <utility>
#include <vector>

#include "cmpcommon.hpp"

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;

template <class Concurrency>
struct dt_types {
    using Vb = CGAL::Triangulation_vertex_base_with_info_3<int32_t, K>;
    using Cb = CGAL::Delaunay_triangulation_cell_base_3<K>;
    using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb, Concurrency>;
    using DT = CGAL::Delaunay_triangulation_3<K, Tds>;
};

/* Cells of the lock grid per axis: the value of CGAL's own parallel
 * insertion example and benchmarks (50^3 = 125,000 locks). */
constexpr int lock_grid_cells = 50;

/*
 * Builds the triangulation of in's distinct points and returns its finite
 * cells as first-input indices in tets. lock_ds is NULL for the sequential
 * triangulation. Returns false (after saying why) for degenerate input.
 */
template <class DT>
bool triangulate(const fdt_bench::input &in, typename DT::Lock_data_structure *lock_ds,
                 std::vector<fdt_ref::tet4> &tets, const char *path,
                 std::shared_ptr<void> &keep)
{
    std::vector<std::pair<Point, int32_t>> pts;
    pts.reserve(in.firsts.size());
    for (int32_t i : in.firsts) {
        const double *c = &in.xyz[3 * (size_t)i];
        pts.emplace_back(Point(c[0], c[1], c[2]), i);
    }
    // Kept alive in keep and freed by the caller after the SUMMARY line,
    // as frontdt frees its result after printing: outside tri_s, inside
    // bench/run's wall_s. The range insert sorts spatially (in parallel for
    // Parallel_tag), then inserts.
    auto *dt = new DT(K(), lock_ds);
    keep = std::shared_ptr<void>(dt);
    dt->insert(pts.begin(), pts.end());
    if (dt->dimension() < 3) {
        std::fprintf(stderr,
                     "cmp_cgal: %s: degenerate input (%zu distinct points, "
                     "dimension %d)\n",
                     path, in.firsts.size(), dt->dimension());
        return false;
    }
    tets.reserve(dt->number_of_finite_cells());
    for (auto c : dt->finite_cell_handles())
        tets.push_back({c->vertex(0)->info(), c->vertex(1)->info(),
                        c->vertex(2)->info(), c->vertex(3)->info()});
    return true;
}

} // namespace

int main(int argc, char **argv)
{
    fdt_bench::args a;
    if (!fdt_bench::parse_args(argc, argv, "cmp_cgal", a))
        return fdt_bench::EXIT_USAGE;
#ifndef CGAL_LINKED_WITH_TBB
    if (a.threads > 0) {
        std::fprintf(stderr, "cmp_cgal: parallel CGAL not available: built "
                     "without TBB\n");
        return fdt_bench::EXIT_UNAVAILABLE;
    }
#endif
    const double t0 = fdt_ref::now_s();
    fdt_bench::input in;
    if (!fdt_bench::read_input("cmp_cgal", a.input, in))
        return fdt_bench::EXIT_USAGE;
    const double t1 = fdt_ref::now_s();

    fdt_ref::merge_duplicates(in.xyz, in.map, in.firsts);
    std::vector<fdt_ref::tet4> tets;
    // The lock grid must outlive the triangulation that points to it, so it
    // is declared first (destroyed last).
    std::shared_ptr<void> keep_locks, keep_dt;
    bool ok;
    if (a.threads == 0) {
        ok = triangulate<dt_types<CGAL::Sequential_tag>::DT>(in, nullptr, tets,
                                                             a.input, keep_dt);
    } else {
#ifdef CGAL_LINKED_WITH_TBB
        using DT = dt_types<CGAL::Parallel_tag>::DT;
        // Exactly N threads for the whole run: TBB's default is every core
        // the process may use, which would make --threads a lie.
        tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                    (size_t)a.threads);
        // The lock grid must cover the points: CGAL maps positions outside
        // it onto its border cells, which serialises those insertions.
        double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
        for (size_t k = 0; k < in.firsts.size(); ++k)
            for (int c = 0; c < 3; ++c) {
                double v = in.xyz[3 * (size_t)in.firsts[k] + (size_t)c];
                if (k == 0 || v < lo[c])
                    lo[c] = v;
                if (k == 0 || v > hi[c])
                    hi[c] = v;
            }
        auto *locks = new DT::Lock_data_structure(
            CGAL::Bbox_3(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]),
            lock_grid_cells);
        keep_locks = std::shared_ptr<void>(locks);
        ok = triangulate<DT>(in, locks, tets, a.input, keep_dt);
#else
        ok = false; // unreachable: refused above
#endif
    }
    if (!ok)
        return fdt_bench::EXIT_DEGENERATE;
    const double t2 = fdt_ref::now_s();

    uint64_t hash = 0;
    if (!fdt_bench::finish_tets("cmp_cgal", a.output, tets, &hash))
        return fdt_bench::EXIT_USAGE;
    const double t3 = fdt_ref::now_s();
    fdt_bench::print_summary(a.threads ? "cgal_par" : "cgal", a.threads ? a.threads : 1,
                             in.n, in.firsts.size(), tets.size(), t1 - t0,
                             t2 - t1, t3 - t2, t3 - t0, hash);
    keep_dt.reset();
    keep_locks.reset();
    return fdt_bench::EXIT_OK;
}
