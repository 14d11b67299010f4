/*
 * The distributed setup of §3.1; see mpi_setup.h. Phases, each collective:
 *
 * 1. Read. A .xyz/.txt/.csv file is cut into p byte ranges at line starts
 *    (rank r: bytes from the first line start at or after S r / p), each
 *    parsed by its rank with the readers' parser (src/io/read/reader.h,
 *    fdt_rd_text_range). Rank 0 reads the file's head first (a header
 *    line, the first point line's column count) and tells everyone. Line
 *    numbers need the lines before a slice: an MPI_Exscan of the slices'
 *    line counts after the parse; only a failing slice is parsed again to
 *    word its error with them (the lowest failing rank's is the file's
 *    first, as a whole read would report). Input ids: an MPI_Exscan of
 *    the slices' point counts. A binary PLY whose elements have fixed
 *    sizes: the header on every rank, then vertices [N r / p, N (r + 1) /
 *    p) by pread (a NaN or infinity anywhere: rank 0 reads the file whole
 *    to word the error as frontdt does). Other formats (.node, ASCII PLY,
 *    PLY with lists): every rank reads the whole input and keeps slice r
 *    of its points; standard input (which reaches
 *    rank 0 alone): rank 0 reads it and scatters the slices.
 * 2. Bisection by exchange (§3.1; the cut rule of src/geom/partition.c): a
 *    group of g ranks (all of them at first) splits into k = g / 2 and
 *    g - k; the cut is on the box's widest axis d at the count partition.c
 *    aims at, found by an exact distributed selection in the total order
 *    (x_d, x_d+1, x_d+2) (pick_cut). Equal points have equal keys and the
 *    equal class at the cut goes wholly to one side, so duplicates never
 *    straddle a cut. An MPI_Alltoallv then spreads each side's points
 *    evenly over that side's ranks, and MPI_Comm_split makes the two
 *    groups of the next level.
 * 3. Merge: equal points now sit on one rank, which hashes its points and
 *    keeps each class's least input id (src/geom/prepare.c's rule, so ids and
 *    hashes equal serial's); the power of two scale is chosen from the
 *    extremes reduced over the ranks, as fdt_prepare chooses it.
 * 4. Trees: each rank builds only its own tree, over global ids [start_r,
 *    start_r+1) (an MPI_Allgather of the counts); every rank rebuilds the
 *    bisection nodes (the boxes the engine's search walks) from each
 *    rank's box and split axes.
 * 5. Seeds: each rank's seed grows from the point a nearest its box's
 *    centre: every rank sends it its points within R of a, and src/front/seed.c
 *    finds a Delaunay tet of that small set. Its circumsphere inside the
 *    ball means no point outside the ball is in it (nor on it), so the
 *    tet is Delaunay for all the points (the perturbation orders points
 *    by their coordinates alone, the same in any subset); otherwise R
 *    grows, at worst past every point. The dimension check: each rank's
 *    affine basis (at most 4 points) spans its points' affine hull, so
 *    the bases of all ranks span the whole input's.
 */
#include "mpi/mpi_setup.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "base/clock.h"
#include "geom/kdtree.h"
#include "geom/predicates.h"
#include "geom/prepare.h"
#include "io/read/reader.h"
#include "front/seed.h"

/* A point in the exchanges: coordinates and an id (the input id in the
 * setup, the global id in the seeds' gathers). 32 bytes. */
typedef struct rec {
    double x[3];
    uint64_t id;
} rec;

/* The bisection is at most log2(FDT_PARTITION_MAX) = 10 levels deep. */
#define SETUP_DEPTH 16

void fdt_mpi_local_free(fdt_mpi_local *L)
{
    free(L->p);
    free(L->orig);
    fdt_partition_free(&L->pt);
    free(L->seeds);
    free(L->seed_xyz);
    free(L->in_id);
    free(L->in_vertex);
    free(L->in_xyz);
    memset(L, 0, sizeof *L);
}

int fdt_mpi_agree(MPI_Comm comm, int err, char *diag, size_t dlen)
{
    int size, rank;
    MPI_Comm_size(comm, &size);
    MPI_Comm_rank(comm, &rank);
    /* (err != 0 ? rank : size), minimised: the lowest failing rank */
    int mine = err ? rank : size, low = size;
    MPI_Allreduce(&mine, &low, 1, MPI_INT, MPI_MIN, comm);
    if (low == size)
        return FDT_OK;
    int e = err;
    MPI_Bcast(&e, 1, MPI_INT, low, comm);
    char msg[512];
    if (rank == low)
        snprintf(msg, sizeof msg, "%s", diag);
    MPI_Bcast(msg, (int)sizeof msg, MPI_CHAR, low, comm);
    msg[sizeof msg - 1] = '\0';
    if (rank != low || !diag[0])
        snprintf(diag, dlen, "%s", msg);
    return e;
}

size_t fdt_mpi_counts(MPI_Comm comm, const int *sc, int *sd, int *rc, int *rd, size_t rec_size,
                      uint64_t *bytes)
{
    int size, rank;
    MPI_Comm_size(comm, &size);
    MPI_Comm_rank(comm, &rank);
    MPI_Alltoall(sc, 1, MPI_INT, rc, 1, MPI_INT, comm);
    size_t nr = 0;
    for (int q = 0, at = 0; q < size; q++) {
        sd[q] = at;
        at += sc[q];
        rd[q] = (int)nr;
        nr += (size_t)rc[q];
        if (q != rank)
            *bytes += (uint64_t)sc[q] * rec_size;
    }
    return nr;
}

size_t fdt_mpi_block_start(uint64_t n, int size, int q)
{
    return (size_t)(n * (uint64_t)q / (uint64_t)size);
}

int fdt_mpi_block_owner(uint64_t n, int size, uint64_t id)
{
    int q = (int)(id * (uint64_t)size / n);
    while (q + 1 < size && fdt_mpi_block_start(n, size, q + 1) <= id)
        q++;
    while (q > 0 && fdt_mpi_block_start(n, size, q) > id)
        q--;
    return q;
}

static int io_err(int rc)
{
    switch (rc) {
    case FDT_IO_OK: return FDT_OK;
    case FDT_IO_ENOMEM: return FDT_ENOMEM;
    case FDT_IO_EEXT: return FDT_EINVAL;
    case FDT_IO_EOPEN: return FDT_EIO;
    default: return FDT_EFORMAT;
    }
}

/* ---- 1. read ------------------------------------------------------------- */

/* How o's input may be read by slices: 1 a regular file of a text point
 * format, 2 a regular PLY file (binary, if fdt_rd_ply_find_layout agrees), 0
 * not at all. */
static int sliceable(const fdt_mpi_setup_opts *o)
{
    if (strcmp(o->input, "-") == 0)
        return 0;
    int f = o->format ? fdt_rd_format_by_name(o->format) : fdt_rd_format_of_path(o->input);
    struct stat st;
    if (stat(o->input, &st) != 0 || !S_ISREG(st.st_mode))
        return 0;
    return f == FDT_RD_XYZ ? 1 : f == FDT_RD_PLY ? 2 : 0;
}

/* This rank's slice as read: n points xyz (owned), the input id of the
 * first (set later for text slices, by the count of the slices before). */
typedef struct slice {
    double *xyz;
    size_t n;
    uint64_t first;
} slice;

/* How the input is read, which rank 0 decides and tells everyone (1: text
 * slices, 2: binary PLY slices, 0: whole), with the PLY's layout for 2
 * into *lay (collective). */
static int read_kind(MPI_Comm comm, const fdt_mpi_setup_opts *o, fdt_rd_ply_layout *lay,
                     char *diag, size_t dlen)
{
    int rank;
    MPI_Comm_rank(comm, &rank);
    int kind = 0;
    memset(lay, 0, sizeof *lay);
    if (rank == 0) {
        kind = sliceable(o);
        if (kind == 2) {
            int lr = fdt_rd_ply_find_layout(o->input, lay, diag, dlen);
            kind = lr == 1 ? 2 : 0; /* errors: the whole read words them */
        }
    }
    MPI_Bcast(&kind, 1, MPI_INT, 0, comm);
    if (kind == 2) {
        unsigned long long lv[8] = {lay->vertex_off, lay->rec, lay->count, lay->off[0],
                                    lay->off[1], lay->off[2], 0, (unsigned long long)lay->big};
        int ty[3] = {lay->type[0], lay->type[1], lay->type[2]};
        MPI_Bcast(lv, 8, MPI_UNSIGNED_LONG_LONG, 0, comm);
        MPI_Bcast(ty, 3, MPI_INT, 0, comm);
        lay->vertex_off = (size_t)lv[0];
        lay->rec = (size_t)lv[1];
        lay->count = lv[2];
        for (int k = 0; k < 3; k++) {
            lay->off[k] = (size_t)lv[3 + k];
            lay->type[k] = ty[k];
        }
        lay->big = (int)lv[7];
    }
    return kind;
}

/* Kind 2: this rank's vertices of a binary PLY of layout lay into *s
 * (collective; the error, if any, the same on every rank). */
static int read_ply_slice(MPI_Comm comm, const fdt_mpi_setup_opts *o,
                          const fdt_rd_ply_layout *lay, slice *s, char *diag, size_t dlen)
{
    int rank, size;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    /* vertices [N r / p, N (r + 1) / p), by pread of their bytes */
    unsigned long long a = lay->count * (unsigned long long)rank / (unsigned long long)size;
    unsigned long long b = lay->count * (unsigned long long)(rank + 1) / (unsigned long long)size;
    s->n = (size_t)(b - a);
    int rc = fdt_rd_ply_range(o->input, lay, a, s->n, &s->xyz, diag, dlen);
    int bad = rc == FDT_IO_EFORMAT, anybad = 0;
    MPI_Allreduce(&bad, &anybad, 1, MPI_INT, MPI_MAX, comm);
    if (anybad) {
        /* a NaN or an infinity: rank 0 reads the file whole, which
         * words the error exactly as frontdt does (only bad files pay) */
        free(s->xyz);
        s->xyz = NULL;
        double *w = NULL;
        size_t wn = 0;
        int err = FDT_EFORMAT;
        if (rank == 0) {
            err = fdt_read_points(o->input, o->format, &w, &wn, diag, dlen);
            fdt_free(w);
            if (!err) {
                snprintf(diag, dlen, "%s: a slice and the whole read disagree", o->input);
                err = FDT_EINTERNAL;
            }
        }
        /* rank 0's message is the one: the others only follow */
        int e0 = err;
        MPI_Bcast(&e0, 1, MPI_INT, 0, comm);
        char m0[512];
        snprintf(m0, sizeof m0, "%s", diag);
        MPI_Bcast(m0, (int)sizeof m0, MPI_CHAR, 0, comm);
        snprintf(diag, dlen, "%s", m0);
        return e0;
    }
    s->first = a;
    return fdt_mpi_agree(comm, io_err(rc), diag, dlen);
}

/* Kind 1: this rank's byte range of a text point file into *s, its errors
 * worded with the file's line numbers (collective; the error, if any, the
 * same on every rank). */
static int read_text_slice(MPI_Comm comm, const fdt_mpi_setup_opts *o, slice *s, char *diag,
                           size_t dlen)
{
    int rank, size;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    int err = FDT_OK;
    fdt_rd_head h;
    memset(&h, 0, sizeof h);
    if (rank == 0)
        err = io_err(fdt_rd_text_head(o->input, &h, diag, dlen));
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK)
        return err;
    uint64_t hv[4] = {h.body, h.body_line, h.ncols, h.size};
    MPI_Bcast(hv, 4, MPI_UINT64_T, 0, comm);
    if (hv[2] == 0) {
        snprintf(diag, dlen, "%s: no points%s", o->input, hv[3] == 0 ? " (empty file)" : "");
        return FDT_EFORMAT;
    }
    /* [begin, end): from the first line start at or after this
     * rank's share of the body, to the next rank's */
    uint64_t body = hv[0], S = hv[3], span = S - body;
    uint64_t want0 = body + span * (uint64_t)rank / (uint64_t)size;
    uint64_t want1 = body + span * (uint64_t)(rank + 1) / (uint64_t)size;
    size_t begin = (size_t)want0, end = (size_t)want1;
    int rc = rank == 0 ? FDT_IO_OK
                       : fdt_rd_text_line_start(o->input, (size_t)want0, &begin, diag, dlen);
    if (rc == FDT_IO_OK && rank + 1 < size)
        rc = fdt_rd_text_line_start(o->input, (size_t)want1, &end, diag, dlen);
    if (end < begin)
        end = begin;
    size_t lines = 0;
    fdt_rd_opts ro;
    fdt_rd_opts_default(&ro);
    ro.format = FDT_RD_XYZ;
    if (rc == FDT_IO_OK)
        rc = fdt_rd_text_range(o->input, &ro, begin, end, (size_t)hv[2], 0, &s->xyz, &s->n,
                               &lines, diag, dlen);
    /* Lines before the slice: the head's and the slices' before it
     * (complete: a slice's parse counts its line ends even when it
     * fails only on a rank after the lowest failing one, whose own
     * count does not matter then). */
    uint64_t ml = lines, before = 0;
    MPI_Exscan(&ml, &before, 1, MPI_UINT64_T, MPI_SUM, comm);
    if (rank == 0)
        before = 0;
    if (rc == FDT_IO_EFORMAT && before + hv[1] > 0) {
        /* word the error with the right line numbers */
        rc = fdt_rd_text_range(o->input, &ro, begin, end, (size_t)hv[2],
                               (size_t)(before + hv[1]), &s->xyz, &s->n, &lines, diag, dlen);
        if (rc == FDT_IO_OK) { /* cannot happen: the same bytes */
            rc = FDT_IO_EFORMAT;
            free(s->xyz);
            s->xyz = NULL;
        }
    }
    return fdt_mpi_agree(comm, io_err(rc), diag, dlen);
}

/* Standard input, which reaches rank 0 alone (mpirun forwards it there):
 * rank 0 reads it and scatters slice r to rank r, into *s (collective;
 * the error, if any, the same on every rank). */
static int read_stdin_slice(MPI_Comm comm, const fdt_mpi_setup_opts *o, slice *s, char *diag,
                            size_t dlen)
{
    int rank, size;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    int err = FDT_OK;
    double *all_xyz = NULL;
    size_t all_n = 0;
    if (rank == 0)
        err = fdt_read_points(o->input, o->format, &all_xyz, &all_n, diag, dlen);
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK)
        return err;
    uint64_t an = all_n;
    MPI_Bcast(&an, 1, MPI_UINT64_T, 0, comm);
    size_t a = (size_t)(an * (uint64_t)rank / (uint64_t)size);
    size_t n = (size_t)(an * (uint64_t)(rank + 1) / (uint64_t)size) - a;
    s->n = n;
    s->first = a;
    int *cnt = rank == 0 ? malloc(2 * (size_t)size * sizeof *cnt) : NULL;
    s->xyz = malloc((3 * n + 1) * sizeof *s->xyz);
    err = s->xyz && (rank != 0 || cnt) ? FDT_OK : FDT_ENOMEM;
    snprintf(diag, dlen, "out of memory reading standard input");
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK) {
        free(cnt);
        fdt_free(all_xyz);
        return err;
    }
    diag[0] = '\0';
    MPI_Datatype pt3;
    MPI_Type_contiguous(3, MPI_DOUBLE, &pt3);
    MPI_Type_commit(&pt3);
    for (int q = 0; cnt && q < size; q++) {
        size_t qa = (size_t)(an * (uint64_t)q / (uint64_t)size);
        cnt[q] = (int)((size_t)(an * (uint64_t)(q + 1) / (uint64_t)size) - qa);
        cnt[size + q] = (int)qa;
    }
    MPI_Scatterv(all_xyz, cnt, cnt ? cnt + size : NULL, pt3, s->xyz, (int)n, pt3, 0, comm);
    MPI_Type_free(&pt3);
    free(cnt);
    fdt_free(all_xyz);
    /* nothing has failed since the last agreement, but every way of
     * reading ends with one */
    return fdt_mpi_agree(comm, FDT_OK, diag, dlen);
}

/* Kind 0 of a file: every rank reads the whole input and keeps slice r of
 * its points, so that the rest of the setup is the same whatever was read
 * (collective; the error, if any, the same on every rank). */
static int read_whole_slice(MPI_Comm comm, const fdt_mpi_setup_opts *o, slice *s, char *diag,
                            size_t dlen)
{
    int rank, size;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    double *all_xyz = NULL;
    size_t all_n = 0;
    int err = fdt_read_points(o->input, o->format, &all_xyz, &all_n, diag, dlen);
    if (!err) {
        size_t a = all_n * (size_t)rank / (size_t)size, b = all_n * (size_t)(rank + 1) / (size_t)size;
        s->n = b - a;
        s->first = a;
        s->xyz = malloc((3 * s->n + 1) * sizeof *s->xyz);
        if (!s->xyz)
            err = FDT_ENOMEM;
        else
            memcpy(s->xyz, all_xyz + 3 * a, 3 * s->n * sizeof *s->xyz);
        fdt_free(all_xyz);
    }
    return fdt_mpi_agree(comm, err, diag, dlen);
}

/* The slices' points as records with input ids, into *out (*nout), and
 * their total into L->n; frees s->xyz (collective). */
static int slice_records(MPI_Comm comm, const fdt_mpi_setup_opts *o, fdt_mpi_local *L, slice *s,
                         rec **out, size_t *nout, char *diag, size_t dlen)
{
    int rank;
    MPI_Comm_rank(comm, &rank);
    size_t n = s->n;
    uint64_t mn = n, tot = 0, off = 0;
    MPI_Allreduce(&mn, &tot, 1, MPI_UINT64_T, MPI_SUM, comm);
    MPI_Exscan(&mn, &off, 1, MPI_UINT64_T, MPI_SUM, comm);
    if (rank == 0)
        off = 0;
    if (L->sliced == 1)
        s->first = off;
    if (tot == 0) {
        snprintf(diag, dlen, "%s: no points", o->input);
        return FDT_EFORMAT;
    }
    if (tot > (uint64_t)INT32_MAX) {
        snprintf(diag, dlen, "%s: more than %d points", o->input, INT32_MAX);
        return FDT_ETOOBIG;
    }
    L->n = (size_t)tot;
    int err = FDT_OK;
    rec *r = malloc((n + 1) * sizeof *r);
    if (!r)
        err = FDT_ENOMEM;
    for (size_t i = 0; r && i < n; i++) {
        memcpy(r[i].x, s->xyz + 3 * i, sizeof r[i].x);
        r[i].id = s->first + i;
    }
    free(s->xyz);
    s->xyz = NULL;
    snprintf(diag, dlen, "out of memory after reading");
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK) {
        free(r);
        return err;
    }
    diag[0] = '\0';
    *out = r;
    *nout = n;
    return FDT_OK;
}

/* This rank's points as records with input ids, into *out (*nout): read
 * by the step for how the input is read, then numbered. */
static int read_slice(MPI_Comm comm, const fdt_mpi_setup_opts *o, fdt_mpi_local *L, rec **out,
                      size_t *nout, char *diag, size_t dlen)
{
    slice s = {NULL, 0, 0};
    fdt_rd_ply_layout lay;
    int kind = read_kind(comm, o, &lay, diag, dlen);
    L->sliced = kind; /* 3 below for standard input */
    int err;
    if (kind == 2) {
        err = read_ply_slice(comm, o, &lay, &s, diag, dlen);
    } else if (kind == 1) {
        err = read_text_slice(comm, o, &s, diag, dlen);
    } else if (strcmp(o->input, "-") == 0) {
        L->sliced = 3;
        err = read_stdin_slice(comm, o, &s, diag, dlen);
    } else {
        err = read_whole_slice(comm, o, &s, diag, dlen);
    }
    if (err == FDT_OK)
        err = slice_records(comm, o, L, &s, out, nout, diag, dlen);
    free(s.xyz);
    return err;
}

/* ---- 2. bisection by exchange -------------------------------------------- */

/* The total order of the cut on axis d: x_d, then x_d+1, then x_d+2. Equal
 * keys are equal points (-0 = +0, as the merge's). */
static int key_cmp(const double *a, const double *b, int d)
{
    for (int j = 0; j < 3; j++) {
        int k = (d + j) % 3;
        if (a[k] < b[k])
            return -1;
        if (a[k] > b[k])
            return 1;
    }
    return 0;
}

/* r[a, b) rearranged into < pivot, == pivot, > pivot: [a, *l1), [*l1,
 * *l2), [*l2, b). */
static void split3(rec *r, size_t a, size_t b, const double *pivot, int d, size_t *l1, size_t *l2)
{
    size_t lt = a, i = a, gt = b;
    while (i < gt) {
        int c = key_cmp(r[i].x, pivot, d);
        if (c < 0) {
            rec t = r[lt];
            r[lt++] = r[i];
            r[i++] = t;
        } else if (c > 0) {
            rec t = r[--gt];
            r[gt] = r[i];
            r[i] = t;
        } else {
            i++;
        }
    }
    *l1 = lt;
    *l2 = gt;
}

/* A sample of pick_cut: a key rotated so that the cut's axis comes first
 * (key[j] = x_(d+j) mod 3: plain lexicographic order is the cut's order,
 * and qsort needs no axis), and the points it stands for. */
typedef struct prop {
    double key[3];
    double w;
} prop;

static int prop_cmp(const void *x, const void *y)
{
    return key_cmp(((const prop *)x)->key, ((const prop *)y)->key, 0);
}

/* x rotated for axis d (into a prop's key), or back (d = 3 - d). */
static void rotate(double *out, const double *x, int d)
{
    for (int j = 0; j < 3; j++)
        out[j] = x[(d + j) % 3];
}

/* Samples a rank sends a round of pick_cut: enough that the two pivots
 * bracket the cut within a few percent of the undecided points, few
 * enough that every rank sorts them all in no time. */
static int samples_per_rank(int gs)
{
    int s = 4096 / gs;
    return s < 16 ? 16 : s > 1024 ? 1024 : s;
}

/*
 * Rearranges r[0, n) so that r[0, *nleft) go left: over the group, the
 * `target` smallest keys on axis d, give or take the class of points equal
 * to the key at the cut, which goes wholly to the side nearer the target.
 * Each round every rank sends samples of its undecided range, each
 * weighted by the points it stands for; the weighted quantiles a margin
 * below and above the target are the pivots lo <= hi; each rank splits its
 * range five ways (< lo, = lo, between, = hi, > hi) and the counts summed
 * over the group say where the cut falls: at a segment's end (done), in a
 * class of equal points (wholly to the nearer side: done), or in a range,
 * which stays undecided. The pivots are undecided points, so every round
 * decides at least their classes: it ends; with good samples the range
 * shrinks to a tenth or less a round.
 */
static void pick_cut(MPI_Comm g, int gs, rec *r, size_t n, uint64_t target, int d, size_t *nleft,
                     prop *props)
{
    size_t a = 0, b = n; /* [0, a) left, [b, n) right, decided */
    uint64_t below = 0;  /* points decided left over the group */
    int S = samples_per_rank(gs);
    for (;;) {
        prop *mine = props + (size_t)gs * (size_t)S; /* S more after the gathered */
        size_t act = b - a;
        for (int j = 0; j < S; j++) {
            if (act == 0 || (size_t)j >= act) {
                mine[j].w = 0;
                memset(mine[j].key, 0, sizeof mine[j].key);
                continue;
            }
            size_t ns = act < (size_t)S ? act : (size_t)S;
            rotate(mine[j].key, r[a + (act * (2 * (size_t)j + 1)) / (2 * ns)].x, d);
            mine[j].w = (double)act / (double)ns;
        }
        MPI_Allgather(mine, 4 * S, MPI_DOUBLE, props, 4 * S, MPI_DOUBLE, g);
        size_t k = 0;
        double total = 0;
        for (size_t i = 0; i < (size_t)gs * (size_t)S; i++)
            if (props[i].w > 0) {
                props[k++] = props[i];
                total += props[i].w;
            }
        if (k == 0)
            break;
        qsort(props, k, sizeof *props, prop_cmp);
        /* the target among the undecided, and a margin of two standard
         * deviations of a quantile estimated from k samples */
        double t = (double)(target - below), margin = 2.0 * total / sqrt((double)k);
        size_t ilo = 0, ihi = k - 1;
        double acc = 0;
        for (size_t i = 0; i < k; i++) {
            acc += props[i].w;
            if (acc < t - margin)
                ilo = i + 1 < k ? i + 1 : i;
            if (acc >= t + margin) {
                ihi = i;
                break;
            }
        }
        if (ilo > ihi)
            ilo = ihi;
        double lo[3], hi[3];
        rotate(lo, props[ilo].key, (3 - d) % 3);
        rotate(hi, props[ihi].key, (3 - d) % 3);
        /* five segments: [a, e1) < lo, [e1, e2) = lo, [e2, e3) between,
         * [e3, e4) = hi, [e4, b) > hi (the last two empty when lo = hi) */
        size_t e[6];
        e[0] = a;
        split3(r, a, b, lo, d, &e[1], &e[2]);
        if (key_cmp(lo, hi, d) == 0) {
            e[3] = e[4] = e[2];
        } else {
            split3(r, e[2], b, hi, d, &e[3], &e[4]);
        }
        e[5] = b;
        uint64_t c[5], sum[5];
        for (int i = 0; i < 5; i++)
            c[i] = e[i + 1] - e[i];
        MPI_Allreduce(c, sum, 5, MPI_UINT64_T, MPI_SUM, g);
        uint64_t want = target - below, C = 0;
        int done = 0;
        for (int i = 0; i < 5; i++) {
            if (want == C) { /* the cut at segment i's start */
                a = b = e[i];
                done = 1;
                break;
            }
            if (want < C + sum[i]) {
                if (i == 1 || i == 3) {
                    /* a class of equal points: wholly to the nearer side */
                    a = b = want - C <= C + sum[i] - want ? e[i] : e[i + 1];
                    done = 1;
                } else {
                    a = e[i];
                    b = e[i + 1];
                    below += C;
                }
                break;
            }
            C += sum[i];
        }
        if (!done && want == C) { /* the cut after every segment */
            a = b = e[5];
            done = 1;
        }
        if (done)
            break;
    }
    *nleft = a;
}

/* The box of r[0, n) (lo > hi when n is 0). */
static void rec_box(const rec *r, size_t n, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            if (r[i].x[k] < lo[k])
                lo[k] = r[i].x[k];
            if (r[i].x[k] > hi[k])
                hi[k] = r[i].x[k];
        }
}

/*
 * The recursive bisection: *r (n records) becomes this rank's part;
 * dims[depth] the axis of each cut above it (-1 below its leaf).
 */
static int bisect(MPI_Comm comm, MPI_Datatype rt, rec **pr, size_t *pn, int dims[SETUP_DEPTH],
                  uint64_t *bytes, char *diag, size_t dlen)
{
    MPI_Comm g;
    MPI_Comm_dup(comm, &g);
    int err = FDT_OK;
    for (int i = 0; i < SETUP_DEPTH; i++)
        dims[i] = -1;
    int gs, gr, depth = 0;
    MPI_Comm_size(g, &gs);
    int *sc = malloc(4 * ((size_t)gs + 1) * sizeof *sc);
    /* pick_cut's samples for any group size g <= gs: (g + 1) S(g) <=
     * max(4096, 16 g) + 1024 */
    prop *props = malloc(((size_t)16 * ((size_t)gs + 1) + 8192) * sizeof *props);
    if (!sc || !props)
        err = FDT_ENOMEM;
    snprintf(diag, dlen, "out of memory in the bisection");
    err = fdt_mpi_agree(comm, err, diag, dlen);
    while (!err && gs > 1) {
        MPI_Comm_rank(g, &gr);
        rec *r = *pr;
        size_t n = *pn;
        int k = gs / 2;
        /* the group's box: the minima of lo and of -hi */
        double lo[3], hi[3], b6[6], g6[6];
        rec_box(r, n, lo, hi);
        for (int j = 0; j < 3; j++) {
            b6[j] = lo[j];
            b6[3 + j] = -hi[j];
        }
        MPI_Allreduce(b6, g6, 6, MPI_DOUBLE, MPI_MIN, g);
        fdt_pnode nd;
        memset(&nd, 0, sizeof nd);
        for (int j = 0; j < 3; j++) {
            nd.lo[j] = g6[j];
            nd.hi[j] = -g6[3 + j];
        }
        uint64_t mn = n, count = 0;
        MPI_Allreduce(&mn, &count, 1, MPI_UINT64_T, MPI_SUM, g);
        /* partition.c's rcb: round(count * k / gs) on the left, less the
         * work shift, on the widest axis (the first of equal ones) */
        uint64_t nleft = (2 * count * (uint64_t)k + (uint64_t)gs) / (2 * (uint64_t)gs);
        int dim = 0;
        if (nleft > 0 && nleft < count) {
            double w = nd.hi[0] - nd.lo[0];
            for (int j = 1; j < 3; j++)
                if (nd.hi[j] - nd.lo[j] > w) {
                    w = nd.hi[j] - nd.lo[j];
                    dim = j;
                }
            nleft -= fdt_partition_work_shift(&nd, (uint32_t)nleft, count, w, k);
        }
        dims[depth++] = dim;
        size_t myleft = 0;
        if (nleft >= count)
            myleft = n;
        else if (nleft > 0)
            pick_cut(g, gs, r, n, nleft, dim, &myleft, props);
        /* Spread: the left side's points in rank order, split evenly
         * over ranks [0, k); the right side's over [k, gs). */
        uint64_t mine[2] = {myleft, n - myleft}, off[2] = {0, 0}, tot[2];
        MPI_Exscan(mine, off, 2, MPI_UINT64_T, MPI_SUM, g);
        if (gr == 0)
            off[0] = off[1] = 0;
        MPI_Allreduce(mine, tot, 2, MPI_UINT64_T, MPI_SUM, g);
        int *scount = sc, *sdisp = sc + gs, *rcount = sc + 2 * gs, *rdisp = sc + 3 * gs;
        for (int q = 0; q < gs; q++)
            scount[q] = 0;
        for (int side = 0; side < 2; side++) {
            int q0 = side ? k : 0, nq = side ? gs - k : k;
            uint64_t T = tot[side];
            /* rank q0 + i gets positions [T i / nq, T (i + 1) / nq) */
            for (int i = 0; i < nq; i++) {
                uint64_t s0 = T * (uint64_t)i / (uint64_t)nq, s1 = T * (uint64_t)(i + 1) / (uint64_t)nq;
                uint64_t a = off[side], b = off[side] + mine[side];
                uint64_t x0 = a > s0 ? a : s0, x1 = b < s1 ? b : s1;
                if (x1 > x0)
                    scount[q0 + i] = (int)(x1 - x0);
            }
        }
        /* record counts fit an int: a side's share is under 2^31 points */
        size_t nr = fdt_mpi_counts(g, scount, sdisp, rcount, rdisp, sizeof(rec), bytes);
        rec *nrec = malloc((nr + 1) * sizeof *nrec);
        int e = nrec ? FDT_OK : FDT_ENOMEM;
        snprintf(diag, dlen, "out of memory in the bisection's exchange");
        /* in the group: the other groups may have fewer levels */
        if ((err = fdt_mpi_agree(g, e, diag, dlen)) != FDT_OK) {
            free(nrec);
            break;
        }
        MPI_Alltoallv(r, scount, sdisp, rt, nrec, rcount, rdisp, rt, g);
        free(r);
        *pr = nrec;
        *pn = nr;
        MPI_Comm ng;
        MPI_Comm_split(g, gr < k ? 0 : 1, gr, &ng);
        MPI_Comm_free(&g);
        g = ng;
        MPI_Comm_size(g, &gs);
    }
    MPI_Comm_free(&g);
    free(sc);
    free(props);
    err = fdt_mpi_agree(comm, err, diag, dlen); /* every group's */
    if (!err)
        diag[0] = '\0';
    return err;
}

/* ---- 3. merge ------------------------------------------------------------ */

/* A hash of a point's coordinates, -0 folded onto +0 (equal points, as
 * key_cmp compares them, hash alike). */
static uint64_t point_mix(const double *x)
{
    uint64_t h = 0x9E3779B97F4A7C15ull;
    for (int k = 0; k < 3; k++) {
        double v = x[k] == 0.0 ? 0.0 : x[k];
        uint64_t u;
        memcpy(&u, &v, sizeof u);
        h = (h ^ u) * 0xBF58476D1CE4E5B9ull;
        h ^= h >> 29;
    }
    return h ^ (h >> 32);
}

/* The classes of equal points among the n records r: each class's first
 * (least) input id survives. A hash table of record indices, one pass:
 * slot[h] (cap entries, a power of two, all UINT32_MAX at first) holds the
 * class's survivor so far, cls[i] the slot of record i's class (a sort of
 * the 32-byte records cost 0.37 s a rank at 1M on 2 ranks). Also ext[0],
 * the greatest |x|, and ext[1], -(the least nonzero |x|), where greater.
 * The number of classes. */
static size_t merge_classes(const rec *r, size_t n, uint32_t *slot, size_t cap, uint32_t *cls,
                            double ext[2])
{
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        size_t h = (size_t)point_mix(r[i].x) & (cap - 1);
        for (;; h = (h + 1) & (cap - 1)) {
            uint32_t q = slot[h];
            if (q == UINT32_MAX) {
                slot[h] = (uint32_t)i;
                m++;
                break;
            }
            if (key_cmp(r[q].x, r[i].x, 0) == 0) {
                if (r[i].id < r[q].id)
                    slot[h] = (uint32_t)i;
                break;
            }
        }
        cls[i] = (uint32_t)h;
        for (int k = 0; k < 3; k++) {
            double ax = fabs(r[i].x[k]);
            if (ax > ext[0])
                ext[0] = ax;
            if (ax != 0.0 && -ax > ext[1])
                ext[1] = -ax;
        }
    }
    return m;
}

/* The n records r after the bisection into this rank's distinct points,
 * scaled (L->p, L->orig, L->nloc), the input's map kept if asked
 * (L->in_*), the counts L->m and L->ndup (collective). */
static int merge_duplicates(MPI_Comm comm, const fdt_mpi_setup_opts *o, fdt_mpi_local *L,
                            const rec *r, size_t n, char *diag, size_t dlen)
{
    size_t cap = 16;
    while (cap < 2 * n)
        cap *= 2;
    uint32_t *slot = malloc(cap * sizeof *slot), *cls = malloc((n + 1) * sizeof *cls);
    int err = slot && cls && n < UINT32_MAX ? FDT_OK : FDT_ENOMEM;
    snprintf(diag, dlen, "out of memory merging the duplicates");
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK) {
        free(slot);
        free(cls);
        return err;
    }
    memset(slot, 0xff, cap * sizeof *slot);
    double ext[2] = {0.0, -INFINITY}; /* max |x|, -(min nonzero |x|) */
    size_t m = merge_classes(r, n, slot, cap, cls, ext);
    double gext[2];
    MPI_Allreduce(ext, gext, 2, MPI_DOUBLE, MPI_MAX, comm);
    L->scale_exp = fdt_prepare_scale_exp(gext[0], -gext[1]);
    L->p = malloc((3 * m + 1) * sizeof *L->p);
    L->orig = malloc((m + 1) * sizeof *L->orig);
    if (o->keep_input) {
        L->in_id = malloc((n + 1) * sizeof *L->in_id);
        L->in_vertex = malloc((n + 1) * sizeof *L->in_vertex);
        L->in_xyz = malloc((3 * n + 1) * sizeof *L->in_xyz);
    }
    err = L->p && L->orig && (!o->keep_input || (L->in_id && L->in_vertex && L->in_xyz))
              ? FDT_OK
              : FDT_ENOMEM;
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK) {
        free(slot);
        free(cls);
        return err;
    }
    diag[0] = '\0';
    size_t j = 0;
    for (size_t i = 0; i < n; i++) {
        uint32_t q = slot[cls[i]];
        if (q == (uint32_t)i) { /* the survivor of its class */
            for (int k = 0; k < 3; k++)
                L->p[3 * j + k] = ldexp(r[i].x[k], L->scale_exp); /* exact */
            L->orig[j++] = (fdt_vid)r[i].id;
        }
        if (o->keep_input) {
            L->in_id[i] = (fdt_vid)r[i].id;
            L->in_vertex[i] = (fdt_vid)r[q].id;
            memcpy(L->in_xyz + 3 * i, r[i].x, sizeof r[i].x);
        }
    }
    L->nloc = m;
    L->nin = o->keep_input ? n : 0;
    free(slot);
    free(cls);
    uint64_t mm = m, gm = 0;
    MPI_Allreduce(&mm, &gm, 1, MPI_UINT64_T, MPI_SUM, comm);
    L->m = (size_t)gm;
    L->ndup = L->n - L->m;
    return FDT_OK;
}

/* ---- 4. trees: the bisection's nodes on every rank ------------------------ */

typedef struct node_ctx {
    fdt_partition *pt;
    const double (*box)[6]; /* each rank's lo, hi */
    const int (*dims)[SETUP_DEPTH];
} node_ctx;

/* partition.c's rcb, replayed from what the ranks told: node id holds
 * parts [p0, p0 + k), its children numbered as rcb numbers them. */
static void make_nodes(node_ctx *c, int id, int p0, int k, int depth)
{
    fdt_partition *pt = c->pt;
    fdt_pnode *nd = &pt->nodes[id];
    nd->begin = pt->start[p0];
    nd->end = pt->start[p0 + k];
    if (k == 1) {
        for (int j = 0; j < 3; j++) {
            nd->lo[j] = c->box[p0][j];
            nd->hi[j] = c->box[p0][3 + j];
        }
        nd->dim = 0;
        nd->left = -1;
        nd->part = p0;
        return;
    }
    int a = k / 2;
    nd->part = -1;
    nd->dim = c->dims[p0][depth] >= 0 ? c->dims[p0][depth] : 0;
    int left = pt->nnodes;
    pt->nnodes += 2;
    nd->left = left;
    make_nodes(c, left, p0, a, depth + 1);
    make_nodes(c, left + 1, p0 + a, k - a, depth + 1);
    const fdt_pnode *l = &pt->nodes[left], *r = l + 1;
    nd = &pt->nodes[id]; /* (the array does not move; for clarity) */
    for (int j = 0; j < 3; j++) {
        nd->lo[j] = l->lo[j] < r->lo[j] ? l->lo[j] : r->lo[j];
        nd->hi[j] = l->hi[j] > r->hi[j] ? l->hi[j] : r->hi[j];
    }
}

/* The partition L->pt: every rank's range of global ids, the bisection
 * nodes from every rank's box and split axes dims, and this rank's own
 * tree of leaf size leaf (collective). */
static int build_partition(MPI_Comm comm, fdt_mpi_local *L, const int dims[SETUP_DEPTH],
                           int leaf, char *diag, size_t dlen)
{
    int rank, size;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    size_t m = L->nloc;
    fdt_partition *pt = &L->pt;
    pt->nparts = size;
    pt->m = (uint32_t)L->m;
    pt->start = malloc(((size_t)size + 1) * sizeof *pt->start);
    pt->nodes = malloc((2 * (size_t)size - 1) * sizeof *pt->nodes);
    pt->trees = calloc((size_t)size, sizeof *pt->trees);
    uint32_t *cnts = malloc((size_t)size * sizeof *cnts);
    double(*box)[6] = malloc((size_t)size * sizeof *box);
    int(*alld)[SETUP_DEPTH] = malloc((size_t)size * sizeof *alld);
    int err = pt->start && pt->nodes && pt->trees && cnts && box && alld ? FDT_OK : FDT_ENOMEM;
    snprintf(diag, dlen, "out of memory for the partition");
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK) {
        free(cnts);
        free(box);
        free(alld);
        return err;
    }
    uint32_t m32 = (uint32_t)m;
    MPI_Allgather(&m32, 1, MPI_UINT32_T, cnts, 1, MPI_UINT32_T, comm);
    pt->start[0] = 0;
    for (int q = 0; q < size; q++)
        pt->start[q + 1] = pt->start[q] + cnts[q];
    L->lo = pt->start[rank];
    double mybox[6];
    fdt_points_box(L->p, 0, (uint32_t)m, mybox, mybox + 3);
    if (m == 0)
        for (int k = 0; k < 3; k++) {
            mybox[k] = INFINITY;
            mybox[3 + k] = -INFINITY;
        }
    MPI_Allgather(mybox, 6, MPI_DOUBLE, box, 6, MPI_DOUBLE, comm);
    MPI_Allgather(dims, SETUP_DEPTH, MPI_INT, alld, SETUP_DEPTH, MPI_INT, comm);
    node_ctx nc = {pt, (const double(*)[6])box, (const int(*)[SETUP_DEPTH])alld};
    pt->nnodes = 1;
    make_nodes(&nc, 0, 0, size, 0);
    free(cnts);
    free(box);
    free(alld);
    /* The engine indexes points by global id; this rank holds ids [lo,
     * lo + m) only, so its arrays are addressed from lo back (no other
     * id of them is ever read: message mode reads other parts' points
     * from their messages alone). */
    err = fdt_partition_build_own(pt, L->p - 3 * (size_t)L->lo, L->orig - L->lo, rank, leaf);
    snprintf(diag, dlen, "rank %d: out of memory building its kd-tree", rank);
    return fdt_mpi_agree(comm, err, diag, dlen);
}

/* ---- 5. seeds ------------------------------------------------------------ */

/* A greedy affine basis of the n points P (distinct): indices into out
 * (at most 4), their count. */
static int affine_basis(const double *P, size_t n, size_t out[4])
{
    int k = 0;
    for (size_t i = 0; i < n && k < 4; i++) {
        const double *q = P + 3 * i;
        int take = k == 0 ? 1
                   : k == 1 ? !(q[0] == P[3 * out[0]] && q[1] == P[3 * out[0] + 1] &&
                                q[2] == P[3 * out[0] + 2])
                   : k == 2 ? !fdt_seed_collinear(P + 3 * out[0], P + 3 * out[1], q)
                            : fdt_orient3d(P + 3 * out[0], P + 3 * out[1], P + 3 * out[2], q,
                                           NULL) != 0;
        if (take)
            out[k++] = i;
    }
    return k;
}

typedef struct ball_ctx {
    const double *P; /* global indexing */
    rec *buf;
    size_t n, cap;
    int nomem;
} ball_ctx;

static int ball_cb(void *user, uint32_t id)
{
    ball_ctx *b = user;
    if (b->n == b->cap) {
        size_t nc = b->cap ? 2 * b->cap : 256;
        rec *x = realloc(b->buf, nc * sizeof *x);
        if (!x) {
            b->nomem = 1;
            return 1;
        }
        b->buf = x;
        b->cap = nc;
    }
    memcpy(b->buf[b->n].x, b->P + 3 * (size_t)id, sizeof b->buf[0].x);
    b->buf[b->n].id = id;
    b->n++;
    return 0;
}

/* A Delaunay tet of the nr points r (global ids) incident to the point of
 * id aid, into v (global ids) and vx (coordinates): 1 if its circumsphere
 * lies inside the ball of radius R about a (or every point is in r), 0 if
 * not (or the points do not span space), <0 an error. */
static int seed_from(const rec *r, size_t nr, uint64_t aid, const double *a, double R, int all,
                     int leaf, uint32_t v[4], double vx[12])
{
    double *P = malloc((3 * nr + 1) * sizeof *P);
    fdt_vid *ix = malloc((nr + 1) * sizeof *ix);
    int res = 0;
    fdt_kdtree t;
    memset(&t, 0, sizeof t);
    if (!P || !ix) {
        res = FDT_ENOMEM;
        goto done;
    }
    size_t ia = SIZE_MAX;
    for (size_t i = 0; i < nr; i++) {
        memcpy(P + 3 * i, r[i].x, 3 * sizeof *P);
        ix[i] = (fdt_vid)i;
        if (r[i].id == aid)
            ia = i;
    }
    size_t bs[4];
    if (ia == SIZE_MAX || affine_basis(P, nr, bs) < 4)
        goto done; /* too few points yet */
    if (fdt_kd_build(&t, P, ix, 0, (uint32_t)nr, leaf) != FDT_OK) {
        res = FDT_ENOMEM;
        goto done;
    }
    uint32_t ta = 0;
    for (size_t i = 0; i < nr; i++)
        if ((size_t)ix[i] == ia)
            ta = (uint32_t)i;
    fdt_kdq kq;
    memset(&kq, 0, sizeof kq);
    uint32_t tv[4];
    int rc = fdt_seed_tet(&t, ta, tv, &kq);
    if (rc == FDT_ENOMEM) {
        res = rc;
        goto done;
    }
    if (rc != FDT_OK)
        goto done;
    double x[3];
    const double *q0 = P + 3 * (size_t)tv[0];
    int inside = all;
    if (!inside && fdt_circumcenter_exact(q0, P + 3 * (size_t)tv[1], P + 3 * (size_t)tv[2],
                                          P + 3 * (size_t)tv[3], x) == 0) {
        double rho = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        double dc[3] = {q0[0] + x[0] - a[0], q0[1] + x[1] - a[1], q0[2] + x[2] - a[2]};
        double d = sqrt(dc[0] * dc[0] + dc[1] * dc[1] + dc[2] * dc[2]);
        /* a relative margin far above the rounding of these few
         * operations (the centre is within 2^-51 of the true one) */
        inside = isfinite(d + rho) && (d + rho) * (1.0 + 1e-9) <= R * (1.0 - 1e-9);
    }
    if (inside) {
        for (int k = 0; k < 4; k++) {
            v[k] = (uint32_t)r[ix[tv[k]]].id;
            memcpy(vx + 3 * k, P + 3 * (size_t)tv[k], 3 * sizeof *vx);
        }
        res = 1;
    }
done:
    fdt_kd_free(&t);
    free(P);
    free(ix);
    return res;
}

typedef struct seed_msg {
    double a[3];
    double R;
    double active;
} seed_msg;

typedef struct seed_out {
    uint32_t v[4];
    int32_t has, pad;
    double x[12];
} seed_out;

static int seed_key_cmp(const void *x, const void *y)
{
    const uint32_t *a = x, *b = y; /* sorted ids first */
    for (int k = 0; k < 4; k++)
        if (a[k] != b[k])
            return a[k] < b[k] ? -1 : 1;
    return 0;
}

/* The point a of tree t nearest its box's centre, as this rank's
 * first ball about it into *me: its id (FDT_NONE, me inactive, when t is
 * empty). P: global indexing; gdiag: the whole box's diagonal; m: the
 * number of distinct points. */
static uint32_t seed_start(const fdt_kdtree *t, const double *P, double gdiag, size_t m,
                           seed_msg *me, fdt_kdq *kq)
{
    if (t->n == 0)
        return FDT_NONE;
    double c[3];
    for (int k = 0; k < 3; k++)
        c[k] = t->nodes[0].lo[k] * 0.5 + t->nodes[0].hi[k] * 0.5;
    uint32_t aid = fdt_kd_nearest(t, c, FDT_NONE, kq);
    memcpy(me->a, P + 3 * (size_t)aid, sizeof me->a);
    /* a first radius holding a few dozen points where they are even:
     * four times the nearest neighbour's distance */
    uint32_t b = fdt_kd_nearest(t, me->a, aid, kq);
    double R = gdiag * cbrt(64.0 / (double)m);
    if (b != FDT_NONE) {
        const double *pb = P + 3 * (size_t)b;
        double d[3] = {pb[0] - me->a[0], pb[1] - me->a[1], pb[2] - me->a[2]};
        R = 4.0 * sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    }
    me->R = R > 0 ? R : gdiag;
    me->active = 1;
    return aid;
}

/* Our points in each active asker's ball (all[q], q < size) into bc[q]:
 * FDT_OK or FDT_ENOMEM. */
static int seed_balls(const fdt_kdtree *t, const double *P, const seed_msg *all, int size,
                      ball_ctx *bc, fdt_kdq *kq)
{
    int e = FDT_OK;
    for (int q = 0; q < size; q++) {
        bc[q].P = P;
        bc[q].n = 0;
        if (all[q].active != 0 && t->n > 0) {
            fdt_kd_ball(t, all[q].a, all[q].R, ball_cb, &bc[q], kq);
            if (bc[q].nomem)
                e = FDT_ENOMEM;
        }
    }
    return e;
}

/* The balls' points sent, bc[q]'s to rank q, and the points of our ball
 * received into *got (*nr); cnt: 4 size counts. e: this rank's error so
 * far, agreed on with the exchange's allocations first (collective). */
static int seed_exchange(MPI_Comm comm, MPI_Datatype rt, const ball_ctx *bc, int *cnt, int e,
                         rec **got, size_t *nr, uint64_t *bytes, char *diag, size_t dlen)
{
    int size;
    MPI_Comm_size(comm, &size);
    int *scount = cnt, *sdisp = cnt + size, *rcount = cnt + 2 * size, *rdisp = cnt + 3 * size;
    for (int q = 0; q < size; q++)
        scount[q] = bc[q].n > (size_t)INT_MAX / 2 ? 0 : (int)bc[q].n;
    *nr = fdt_mpi_counts(comm, scount, sdisp, rcount, rdisp, sizeof(rec), bytes);
    size_t ns = (size_t)sdisp[size - 1] + (size_t)scount[size - 1];
    /* one send buffer: the balls in rank order */
    rec *sb = malloc((ns + 1) * sizeof *sb);
    free(*got);
    *got = malloc((*nr + 1) * sizeof **got);
    if (!sb || !*got)
        e = FDT_ENOMEM;
    snprintf(diag, dlen, "out of memory finding the seeds");
    int err = fdt_mpi_agree(comm, e, diag, dlen);
    if (err != FDT_OK) {
        free(sb);
        return err;
    }
    for (int q = 0; q < size; q++)
        if (scount[q] > 0)
            memcpy(sb + sdisp[q], bc[q].buf, (size_t)scount[q] * sizeof *sb);
    MPI_Alltoallv(sb, scount, sdisp, rt, *got, rcount, rdisp, rt, comm);
    free(sb);
    return FDT_OK;
}

/* One try at this rank's seed from the nr points got of its ball me about
 * point aid: found, into *so, with me made inactive; else the ball
 * doubled. FDT_OK or <0 an error. */
static int seed_try(const rec *got, size_t nr, uint32_t aid, double gdiag, int leaf,
                    seed_msg *me, seed_out *so)
{
    /* the ball holds every point once R reaches past all of them */
    int everything = me->R > 2.0 * gdiag;
    int r = seed_from(got, nr, aid, me->a, me->R, everything, leaf, so->v, so->x);
    if (r < 0)
        return r;
    if (r == 1) {
        so->has = 1;
        me->active = 0;
    } else {
        me->R *= 2.0;
    }
    return FDT_OK;
}

/* Every rank's seed so gathered and deduplicated by their sorted ids into
 * L->seeds, in rank order: the same on every rank (collective). */
static int keep_seeds(MPI_Comm comm, fdt_mpi_local *L, const seed_out *so, char *diag,
                      size_t dlen)
{
    int size;
    MPI_Comm_size(comm, &size);
    int err = FDT_OK;
    seed_out *so_all = malloc((size_t)size * sizeof *so_all);
    if (!so_all)
        err = FDT_ENOMEM;
    snprintf(diag, dlen, "out of memory gathering the seeds");
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK) {
        free(so_all);
        return err;
    }
    MPI_Allgather(so, (int)sizeof *so, MPI_BYTE, so_all, (int)sizeof *so, MPI_BYTE, comm);
    uint32_t(*key)[8] = malloc((size_t)size * sizeof *key);
    L->seeds = malloc((size_t)size * sizeof *L->seeds);
    L->seed_xyz = malloc((size_t)size * sizeof *L->seed_xyz);
    int ns = 0, e = key && L->seeds && L->seed_xyz ? FDT_OK : FDT_ENOMEM;
    for (int q = 0; !e && q < size; q++) {
        if (!so_all[q].has)
            continue;
        uint32_t s[4];
        memcpy(s, so_all[q].v, sizeof s);
        for (int i = 1; i < 4; i++)
            for (int j = i; j > 0 && s[j - 1] > s[j]; j--) {
                uint32_t x = s[j];
                s[j] = s[j - 1];
                s[j - 1] = x;
            }
        int dup = 0;
        for (int i = 0; i < ns && !dup; i++)
            dup = seed_key_cmp(key[i], s) == 0;
        if (dup)
            continue;
        memcpy(key[ns], s, sizeof s);
        memcpy(L->seeds[ns], so_all[q].v, sizeof L->seeds[0]);
        memcpy(L->seed_xyz[ns], so_all[q].x, sizeof L->seed_xyz[0]);
        ns++;
    }
    L->nseeds = ns;
    free(key);
    free(so_all);
    snprintf(diag, dlen, "out of memory keeping the seeds");
    err = fdt_mpi_agree(comm, e, diag, dlen);
    if (!err && ns == 0) {
        snprintf(diag, dlen, "internal error: no seed tetrahedron found");
        err = FDT_EINTERNAL;
    }
    return err;
}

/* Every rank's seed, deduplicated into L->seeds (collective): rounds in
 * which every rank sends the active askers their points in their balls and
 * tries its own seed, until no rank is active; then the seeds kept. */
static int find_seeds(MPI_Comm comm, MPI_Datatype rt, fdt_mpi_local *L, int leaf, char *diag,
                      size_t dlen)
{
    int rank, size;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    const fdt_kdtree *t = &L->pt.trees[rank];
    const double *P = L->p - 3 * (size_t)L->lo; /* global indexing */
    const fdt_pnode *root = &L->pt.nodes[0]; /* the whole input's box */
    double gd[3] = {root->hi[0] - root->lo[0], root->hi[1] - root->lo[1],
                    root->hi[2] - root->lo[2]};
    double gdiag = sqrt(gd[0] * gd[0] + gd[1] * gd[1] + gd[2] * gd[2]);
    seed_msg me = {{0, 0, 0}, 0, 0};
    fdt_kdq kq;
    memset(&kq, 0, sizeof kq);
    uint32_t aid = seed_start(t, P, gdiag, L->m, &me, &kq);
    seed_out so;
    memset(&so, 0, sizeof so);
    seed_msg *all = malloc((size_t)size * sizeof *all);
    int *cnt = malloc(4 * (size_t)size * sizeof *cnt);
    ball_ctx *bc = calloc((size_t)size, sizeof *bc);
    rec *got = NULL;
    int err = all && cnt && bc ? FDT_OK : FDT_ENOMEM;
    snprintf(diag, dlen, "out of memory finding the seeds");
    err = fdt_mpi_agree(comm, err, diag, dlen);
    while (!err) {
        MPI_Allgather(&me, 5, MPI_DOUBLE, all, 5, MPI_DOUBLE, comm);
        int any = 0;
        for (int q = 0; q < size; q++)
            any |= all[q].active != 0;
        if (!any)
            break;
        int e = seed_balls(t, P, all, size, bc, &kq);
        size_t nr = 0;
        err = seed_exchange(comm, rt, bc, cnt, e, &got, &nr, &L->bytes_sent, diag, dlen);
        if (err != FDT_OK)
            break;
        e = me.active != 0 ? seed_try(got, nr, aid, gdiag, leaf, &me, &so) : FDT_OK;
        snprintf(diag, dlen, "rank %d: out of memory finding its seed", rank);
        if ((err = fdt_mpi_agree(comm, e, diag, dlen)) != FDT_OK)
            break;
    }
    free(got);
    for (int q = 0; bc && q < size; q++)
        free(bc[q].buf);
    free(bc);
    free(all);
    free(cnt);
    if (err)
        return err;
    return keep_seeds(comm, L, &so, diag, dlen);
}

/* The dimension check over every rank's affine basis (collective). */
static int check_dimension(MPI_Comm comm, const fdt_mpi_local *L, const char *path, char *diag,
                           size_t dlen)
{
    int size;
    MPI_Comm_size(comm, &size);
    if (L->m < 4) {
        snprintf(diag, dlen, "%s: only %zu distinct point%s: a tetrahedralization needs at least 4",
                 path, L->m, L->m == 1 ? "" : "s");
        return FDT_EDEGENERATE;
    }
    /* 4 points a rank: coordinates and input id, unused ones with id -1 */
    double mine[16], *all = malloc((size_t)size * sizeof mine);
    size_t bs[4];
    int k = affine_basis(L->p, L->nloc, bs);
    for (int i = 0; i < 4; i++) {
        if (i < k) {
            memcpy(mine + 4 * i, L->p + 3 * bs[i], 3 * sizeof *mine);
            mine[4 * i + 3] = (double)L->orig[bs[i]];
        } else {
            memset(mine + 4 * i, 0, 3 * sizeof *mine);
            mine[4 * i + 3] = -1;
        }
    }
    int e = all ? FDT_OK : FDT_ENOMEM;
    int any = e;
    MPI_Allreduce(&e, &any, 1, MPI_INT, MPI_MIN, comm);
    if (any) {
        free(all);
        snprintf(diag, dlen, "out of memory checking the dimension");
        return FDT_ENOMEM;
    }
    MPI_Allgather(mine, 16, MPI_DOUBLE, all, 16, MPI_DOUBLE, comm);
    double *P = malloc((size_t)size * 12 * sizeof *P);
    fdt_vid *id = malloc((size_t)size * 4 * sizeof *id);
    size_t n = 0;
    if (P && id)
        for (int q = 0; q < 4 * size; q++)
            if (all[4 * q + 3] >= 0) {
                memcpy(P + 3 * n, all + 4 * q, 3 * sizeof *P);
                id[n++] = (fdt_vid)all[4 * q + 3];
            }
    int err = FDT_OK;
    if (!P || !id) {
        snprintf(diag, dlen, "out of memory checking the dimension");
        err = FDT_ENOMEM;
    } else {
        k = affine_basis(P, n, bs);
        if (k == 2) {
            snprintf(diag, dlen, "%s: all %zu distinct points are collinear (on the line "
                     "through input points %d and %d)", path, L->m, (int)id[bs[0]],
                     (int)id[bs[1]]);
            err = FDT_EDEGENERATE;
        } else if (k == 3) {
            snprintf(diag, dlen, "%s: all %zu distinct points are coplanar (in the plane of "
                     "input points %d, %d and %d)", path, L->m, (int)id[bs[0]], (int)id[bs[1]],
                     (int)id[bs[2]]);
            err = FDT_EDEGENERATE;
        }
    }
    free(all);
    free(P);
    free(id);
    return err;
}

/* ---- the setup ----------------------------------------------------------- */

int fdt_mpi_setup(MPI_Comm comm, const fdt_mpi_setup_opts *o, fdt_mpi_local *L, char *diag,
                  size_t dlen)
{
    memset(L, 0, sizeof *L);
    diag[0] = '\0';
    int size;
    MPI_Comm_size(comm, &size);
    int leaf = o->leaf_size > 0 ? o->leaf_size : FDT_DEFAULT_LEAF;
    if (size > FDT_PARTITION_MAX) {
        snprintf(diag, dlen, "at most %d ranks", FDT_PARTITION_MAX);
        return FDT_EINVAL;
    }
    MPI_Datatype rt;
    MPI_Type_contiguous((int)sizeof(rec), MPI_BYTE, &rt);
    MPI_Type_commit(&rt);
    rec *r = NULL;
    size_t n = 0;
    double t0 = fdt_now_s();
    int err = read_slice(comm, o, L, &r, &n, diag, dlen);
    double t1 = fdt_now_s();
    L->t[FDT_MPI_T_READ] = t1 - t0;
    int dims[SETUP_DEPTH];
    if (!err)
        err = bisect(comm, rt, &r, &n, dims, &L->bytes_sent, diag, dlen);
    double t2 = fdt_now_s();
    L->t[FDT_MPI_T_EXCHANGE] = t2 - t1;
    if (err)
        goto fail;
    err = merge_duplicates(comm, o, L, r, n, diag, dlen);
    free(r);
    r = NULL;
    if (err)
        goto fail;
    double t3 = fdt_now_s();
    L->t[FDT_MPI_T_MERGE] = t3 - t2;
    err = check_dimension(comm, L, strcmp(o->input, "-") == 0 ? "stdin" : o->input, diag, dlen);
    if (!err)
        err = build_partition(comm, L, dims, leaf, diag, dlen);
    if (err)
        goto fail;
    double t4 = fdt_now_s();
    L->t[FDT_MPI_T_TREES] = t4 - t3;
    err = find_seeds(comm, rt, L, leaf, diag, dlen);
    L->t[FDT_MPI_T_SEEDS] = fdt_now_s() - t4;
    if (err)
        goto fail;
    diag[0] = '\0';
    MPI_Type_free(&rt);
    return FDT_OK;
fail:
    free(r);
    fdt_mpi_local_free(L);
    MPI_Type_free(&rt);
    return err;
}
