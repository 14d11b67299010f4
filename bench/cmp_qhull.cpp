/*
 * cmp_qhull IN.xyz [OUT.tets]
 *
 * Qhull's Delaunay triangulation (reentrant libqhull_r) as a benchmark
 * peer: the lower hull of the points lifted to the paraboloid, with
 * qdelaunay's options for 3-d input, "d Qbb Qz" (Qbb: scale the lifted
 * coordinate to the others' range; Qz: a point at infinity, which keeps
 * cospherical inputs from failing), plus Qt (triangulated output: a merged
 * non-simplicial facet is split into tetrahedra, some of them flat on
 * cospherical input). Qhull is floating point with facet merging, not
 * exact: on inputs in general position its tets are the Delaunay ones; on
 * cospherical ones its triangulation of a merged facet is its own, so
 * bench/run compares its hash to the others only where the mesh is unique.
 * Written in C++ only to share tests/refcommon.hpp (reader, duplicate
 * merge, hash) with the other comparators; Qhull itself is C.
 * Sequential: --threads other than 0 or 1 exits 4 (not available).
 *
 * Times, SUMMARY line and exit codes: bench/cmpcommon.hpp.
 */
#include <libqhull_r/libqhull_r.h>

#include <vector>

#include "cmpcommon.hpp"

namespace {

/* The elements of a Qhull set: a NULL-terminated array of pointers
 * (qset_r.h), read directly rather than through Qhull's loop macros, which
 * bind hidden variable names. */
template <class T>
T *set_elem(const setT *s, int i)
{
    return static_cast<T *>(s->e[i].p);
}

/* Frees Qhull's memory when main returns: after the SUMMARY line on
 * success, as frontdt frees its result after printing (outside tri_s,
 * inside bench/run's wall_s). */
struct qhull_guard {
    qhT *qh;
    ~qhull_guard()
    {
        qh_freeqhull(qh, !qh_ALL);
        int curlong, totlong;
        qh_memfreeshort(qh, &curlong, &totlong);
    }
};

} // namespace

int main(int argc, char **argv)
{
    fdt_bench::args a;
    if (!fdt_bench::parse_args(argc, argv, "cmp_qhull", a))
        return fdt_bench::EXIT_USAGE;
    if (a.threads > 1) {
        std::fprintf(stderr, "cmp_qhull: Qhull is sequential: %d threads "
                     "not available\n", a.threads);
        return fdt_bench::EXIT_UNAVAILABLE;
    }
    const double t0 = fdt_ref::now_s();
    fdt_bench::input in;
    if (!fdt_bench::read_input("cmp_qhull", a.input, in))
        return fdt_bench::EXIT_USAGE;
    const double t1 = fdt_ref::now_s();

    fdt_ref::merge_duplicates(in.xyz, in.map, in.firsts);
    const std::vector<int32_t> &firsts = in.firsts;
    if (firsts.size() < 5) {
        // Qhull needs dim + 2 points for a 4-d (lifted) hull.
        std::fprintf(stderr, "cmp_qhull: %s: only %zu distinct points\n",
                     a.input, firsts.size());
        return fdt_bench::EXIT_DEGENERATE;
    }
    std::vector<coordT> pts(3 * firsts.size());
    for (size_t k = 0; k < firsts.size(); ++k)
        for (size_t c = 0; c < 3; ++c)
            pts[3 * k + c] = in.xyz[3 * (size_t)firsts[k] + c];

    qhT qh_storage;
    qhT *qh = &qh_storage;
    QHULL_LIB_CHECK
    qh_zero(qh, stderr);
    qhull_guard guard{qh};
    char options[] = "qhull d Qbb Qz Qt";
    int rc = qh_new_qhull(qh, 3, (int)firsts.size(), pts.data(), False,
                          options, nullptr, stderr);
    std::vector<fdt_ref::tet4> tets;
    bool bad_id = false;
    if (rc == qh_ERRnone) {
        // Every facet of the lower hull is a Delaunay tet; the facet list
        // ends with a sentinel whose next is NULL.
        for (facetT *f = qh->facet_list; f && f->next; f = f->next) {
            if (f->upperdelaunay)
                continue;
            fdt_ref::tet4 t{};
            int k = 0;
            for (int i = 0; set_elem<vertexT>(f->vertices, i); ++i) {
                int id = qh_pointid(qh, set_elem<vertexT>(f->vertices, i)->point);
                if (k == 4 || id < 0 || (size_t)id >= firsts.size()) {
                    bad_id = true;
                    break;
                }
                t[(size_t)k++] = firsts[(size_t)id];
            }
            if (k != 4)
                bad_id = true;
            if (bad_id)
                break;
            tets.push_back(t);
        }
    }
    if (rc != qh_ERRnone) {
        std::fprintf(stderr, "cmp_qhull: %s: Qhull failed with code %d\n",
                     a.input, rc);
        return rc == qh_ERRsingular ? fdt_bench::EXIT_DEGENERATE
                                    : fdt_bench::EXIT_LIBRARY;
    }
    if (bad_id) {
        std::fprintf(stderr, "cmp_qhull: %s: a Delaunay facet without 4 input "
                     "vertices\n", a.input);
        return fdt_bench::EXIT_LIBRARY;
    }
    const double t2 = fdt_ref::now_s();

    uint64_t hash = 0;
    if (!fdt_bench::finish_tets("cmp_qhull", a.output, tets, &hash))
        return fdt_bench::EXIT_USAGE;
    const double t3 = fdt_ref::now_s();
    fdt_bench::print_summary("qhull", 1, in.n, firsts.size(), tets.size(),
                             t1 - t0, t2 - t1, t3 - t2, t3 - t0, hash);
    return fdt_bench::EXIT_OK;
}
