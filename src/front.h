/*
 * The serial advancing front (§2.2): the reference every parallel mode
 * must equal.
 */
#ifndef FDT_FRONT_H
#define FDT_FRONT_H

#include <stddef.h>
#include <stdint.h>
#include "frontdt.h"
#include "kdtree.h"

/* Growable output: tets (4 global ids each, positively oriented), their
 * neighbours (optional) and hull faces (3 ids, outward). */
typedef struct fdt_meshbuf {
    uint32_t *tets;
    size_t ntets, tcap;
    int64_t *nbrs;      /* NULL unless wanted; 4 per tet, -1 on the hull */
    uint32_t *hull;
    size_t nhull, hcap;
} fdt_meshbuf;

int fdt_meshbuf_init(fdt_meshbuf *mb, size_t expected_tets, int want_nbrs);
void fdt_meshbuf_free(fdt_meshbuf *mb);
/* Appends tet v (positively oriented); returns its id or -1 (no memory). */
int64_t fdt_meshbuf_add_tet(fdt_meshbuf *mb, const uint32_t v[4]);
int fdt_meshbuf_add_hull(fdt_meshbuf *mb, const uint32_t v[3]);

/* Work counters filled by the front. */
typedef struct fdt_front_stats {
    size_t faces_advanced, max_front;
    fdt_kdq kq;
    /* The insertion mesh (src/oracle.h): faces it answered, of those found
     * by a walk around a vertex, fronts (parts) that built one, and the
     * seconds they took. */
    size_t mesh_faces, star_walks, mesh_parts;
    double t_mesh;
} fdt_front_stats;

/* Triangulates all points of tree t (ids [t->base, t->base + t->n)),
 * starting from a seed near point `start`; search is an fdt_search
 * (src/oracle.h: how each face's apex is found). */
int fdt_front_serial(const fdt_kdtree *t, uint32_t start, int search, fdt_meshbuf *out,
                     fdt_progress_fn progress, void *puser,
                     fdt_front_stats *st);

/* The kd search's first `faces` faces of the front over tree t, for their
 * work counters in st only (the tets are dropped): what src/oracle.c's
 * probe measures. */
int fdt_front_probe(const fdt_kdtree *t, uint32_t start, size_t faces, fdt_front_stats *st);

/* The outward faces of a positively oriented tet: face i is opposite
 * vertex i and has that vertex on its negative side. */
extern const int fdt_tet_face[4][3];

#endif
