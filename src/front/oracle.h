/*
 * Which apex oracle a front uses (bench/NOTES.md, entry 51).
 *
 * The apex of a front face is the first open-side point of the pencil of
 * spheres through the face's circle (§2.2). Two exact ways find it:
 *   - the kd search (src/geom/kdtree.c): certifies the sphere empty by testing
 *     every point the tree cannot exclude; ~90 points a face on uniform
 *     clouds, but thousands where many points lie near the sphere
 *     (cylinders, rotated lattices, near-cospherical sets, flat scans);
 *   - the insertion mesh (src/mesh/insert.c): the part's own points
 *     triangulated once by Bowyer-Watson insertion; the apex is the vertex
 *     across the face, one array read when the face came from a tet the
 *     mesh gave.
 * The perturbed Delaunay tetrahedralization is unique, so both give the
 * same apex and may be mixed face by face. The mesh is a read-only
 * certificate; tets are still emitted one by one by the front, final when
 * built. Which one a front uses is its search's row (src/front/search.c);
 * no rule switches a front from one to the other any more (the serial
 * front's cost rule went with issue 31: the insertion engines take the
 * runs it served, src/api/api.c's pick_engine).
 *
 * In a part of the parallel engine the mesh holds only the part's points:
 * its answer is the first of the part's points in the pencil, and the
 * caller still asks the other parts (their points may come earlier), as
 * after its own kd search.
 */
#ifndef FDT_ORACLE_H
#define FDT_ORACLE_H

#include <stddef.h>
#include <stdint.h>
#include "frontdt.h"
#include "mesh/insert.h"
#include "geom/kdtree.h"

/* Which oracle a front uses (a search's row, src/front/search.c, says
 * which a front gets). */
typedef enum fdt_oracle_policy {
    FDT_ORACLE_KD,     /* the kd search only: no mesh is ever built */
    FDT_ORACLE_MESH    /* the mesh, built at the first tick */
} fdt_oracle_policy;

typedef struct fdt_oracle {
    const fdt_kdtree *t;  /* borrowed: the part's tree (its points) */
    int state;            /* 0: the mesh to build at the next tick (the mesh
                             policy); 1: mesh; -1: the kd search (the kd
                             policy, or no mesh could be built) */
    fdt_ins mesh;         /* owned, valid when state == 1 and !gm */
    const fdt_ins *gm;    /* borrowed: a mesh of every point (shared by
                             all parts, fdt_oracle_share), or NULL */
    uint32_t *mt;         /* owned: mesh tet of output tet i, FDT_NONE unknown */
    fdt_ins_query sq;     /* scratch of fdt_oracle_offer_star */
    size_t mtcap;
    /* Statistics. */
    size_t mesh_faces;    /* faces whose apex the mesh gave */
    size_t star_walks;    /* of those, found by a walk around a vertex */
    size_t star_offers;   /* faces with another part's vertex answered by
                             fdt_oracle_offer_star */
    size_t switched_at;   /* faces advanced when the mesh was built (0: never) */
    double t_mesh;        /* seconds building the mesh */
    /* FDT_ECHECK once a mesh it built failed its certificate (src/mesh/
     * certify.h; err_what says which check): the caller stops the run. */
    int err;
    const char *err_what;
    size_t certified;     /* finite tets of the meshes it certified */
    double t_certify;     /* seconds certifying them */
} fdt_oracle;

/* The weight of one exact test in the kd search's cost, counted in points
 * tested: a point test costs ~8 ns inside the walk, an exact test that
 * leaves the filter 0.3 us (expansions) to 2 us (GMP), so one exact test
 * weighs as ~150 points. The probe costs its faces this way
 * (src/front/probe.c). */
#define FDT_ORACLE_EXACT_WEIGHT 150

/* What an insertion mesh of n points takes at its peak, in bytes: about
 * 220 kept a point (src/mesh/insert.h) plus the build's scratch and the tet
 * array's growth, and the oracle's table of mesh tets (4 bytes an output
 * tet). */
#define FDT_ORACLE_MESH_BYTES 330.0

void fdt_oracle_init(fdt_oracle *o, const fdt_kdtree *t, fdt_oracle_policy policy);
void fdt_oracle_free(fdt_oracle *o);

/*
 * Called before each face is advanced, with the front's running counters
 * (faces advanced so far, and the kd work in kq). With the mesh policy the
 * first call builds the mesh (counting its exact tests in kq) and
 * certifies it; a part whose points do not span 3-D, or a build that runs
 * out of memory, stays on the kd search; a mesh that fails its certificate
 * sets o->err (FDT_ECHECK), which the caller must check. Nothing after.
 */
void fdt_oracle_tick(fdt_oracle *o, size_t faces, fdt_kdq *kq);

/*
 * The mesh's answer for front face f (open side orient3d(f0,f1,f2,x) > 0),
 * whose closed-side tet is output tet ctid (-1: none known) with vertex
 * copp opposite f. Returns 1 when the mesh holds f: *apex is the first of
 * the part's points in the pencil (FDT_NONE: no point of the part on the
 * open side) and *mtet the mesh tet of (f, apex) to note for the new tet.
 * Returns 0 when the mesh is not in use or f is not one of its faces (a
 * vertex of another part): the caller runs the kd search.
 */
int fdt_oracle_apex(fdt_oracle *o, const uint32_t f[3], int64_t ctid, uint32_t copp,
                    uint32_t *apex, uint32_t *mtet);

/*
 * Makes o answer from gm, the DT of every point of the run (built once by
 * fdt_ins_build_parallel and read by every part): then each answer is the
 * apex itself, not just the first of the part's points, and no other part
 * need be asked. gm is borrowed and must outlive o; o never switches.
 */
void fdt_oracle_share(fdt_oracle *o, const fdt_ins *gm);

/*
 * Builds the part's mesh now, whatever the policy (the wall engine of
 * src/par/engine.c builds every part's mesh before its front): state 1 and
 * a certified mesh, or state -1 (fewer than 4 points, points that do not
 * span 3-D, no memory: the kd search answers). Returns FDT_ECHECK when the
 * mesh failed its certificate (o->err, o->err_what), else FDT_OK.
 */
int fdt_oracle_build(fdt_oracle *o, fdt_kdq *kq);

/*
 * For a face f with a vertex of another part (fdt_oracle_apex cannot find
 * it in the part's mesh) whose lowest vertex f[0] is the part's: offers
 * every mesh neighbour of f[0] to the search state ap (fdt_ins_star_vertices:
 * the first of the part's points in the pencil is among them), so that
 * ap->best is the first of the part's points, as the kd search of the
 * part would leave it. Returns 1 when it did; 0 when it cannot (no mesh, a
 * shared mesh, f[0] not in it, a star too large): the caller searches the
 * part's tree; FDT_ENOMEM.
 */
int fdt_oracle_offer_star(fdt_oracle *o, const uint32_t f[3], fdt_apex *ap, fdt_kdq *kq);

/* Notes that output tet tid is mesh tet mtet (FDT_NONE: not known). Only
 * stores while the mesh is in use. FDT_OK or FDT_ENOMEM. */
int fdt_oracle_note(fdt_oracle *o, int64_t tid, uint32_t mtet);

#endif
