/* The Voronoi cells of a distributed run; see mpi_cells.h. */
#include "mpi/mpi_cells.h"

#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "base/mem.h"
#include "io/write/cells.h"
#include "geom/morton.h"
#include "mesh/voronoi.h"
#include "mpi/mpi_output.h"

/* What the steps share. */
typedef struct cells_run {
    MPI_Comm comm;
    int rank, size;
    const fdt_mpi_local *L;
    const fdt_mpi_out *r;
    const fdt_mpi_cells_opts *o;
    double box[6];
    int ed;                /* fdt_voronoi_scale's exponent of box */
    size_t lo, nmine;      /* this rank's block of input ids */
    /* the points of the block's stars, distinct, by input id */
    fdt_vid *ids;
    double *xyz;
    size_t npts;
    uint32_t *tets;        /* the stars' tets, 4 indices into ids each */
    size_t ntets;
    uint8_t *hull;         /* by index into ids: a hull vertex */
    /* the block's input points: vertex[j] the vertex of input id lo + j,
     * at pts + 3 j */
    fdt_vid *vertex;
    double *pts;
    fdt_voronoi *cells, *merged;
    uint64_t bytes;        /* sent to other ranks */
    uint64_t written;
    char *diag;
    size_t dlen;
} cells_run;

/* The lowest failing rank's code and message to every rank. */
static int agree(cells_run *c, int err)
{
    return fdt_mpi_agree(c->comm, err, c->diag, c->dlen);
}

static int oom(cells_run *c, const char *what)
{
    snprintf(c->diag, c->dlen, "out of memory %s", what);
    return FDT_ENOMEM;
}

/*
 * One exchange of records of rec bytes (collective): sb holds sc[q] of
 * them for rank q, grouped by rank in rank order; cnt's four rows of
 * size ints are sc itself, then the send starts, the receive counts and
 * the receive starts (by source), which this fills. *rb: what came, *nr
 * records (owned by the caller, also on failure). FDT_OK or FDT_ENOMEM
 * on every rank.
 */
static int exchange(cells_run *c, const void *sb, int *cnt, size_t rec, void **rb, size_t *nr,
                    const char *what)
{
    int size = c->size, *sd = cnt + size, *rc = cnt + 2 * size, *rd = cnt + 3 * size;
    *nr = fdt_mpi_counts(c->comm, cnt, sd, rc, rd, rec, &c->bytes);
    *rb = malloc((*nr + 1) * rec);
    int err = *rb ? FDT_OK : oom(c, what);
    if ((err = agree(c, err)) != FDT_OK)
        return err;
    MPI_Datatype t;
    MPI_Type_contiguous((int)rec, MPI_BYTE, &t);
    MPI_Type_commit(&t);
    MPI_Alltoallv(sb, cnt, sd, t, *rb, rc, rd, t, c->comm);
    MPI_Type_free(&t);
    return FDT_OK;
}

/* The start of each rank's records in a send buffer: the prefix sums of
 * the counts c (a counting sort's; each fill moves them on, and a second
 * call puts them back). */
static void starts(const int *c, int *d, int size)
{
    for (int q = 0, at = 0; q < size; q++) {
        d[q] = at;
        at += c[q];
    }
}

/* ---- 1. the box ---------------------------------------------------------- */

/* o's box, every point checked inside it (the least input id outside is
 * named, as frontdt's single check names the first), or the bounding box
 * of every rank's points; then its scale. */
static int the_box(cells_run *c)
{
    const fdt_mpi_local *L = c->L;
    fdt_voronoi_options vo;
    fdt_default_voronoi_options(&vo);
    vo.box_given = c->o->box_given;
    memcpy(vo.box, c->o->box, sizeof vo.box);
    /* the box itself (no points): empty or not finite */
    int err = fdt_voronoi_box_of(NULL, NULL, 0, &vo, c->box, c->diag, c->dlen);
    if ((err = agree(c, err)) != FDT_OK)
        return err;
    if (c->o->box_given) {
        uint64_t least = UINT64_MAX, all = 0;
        size_t at = 0;
        for (size_t i = 0; i < L->nin; i++) {
            const double *p = L->in_xyz + 3 * i;
            int out = 0;
            for (int k = 0; k < 3; k++)
                out |= p[k] < c->box[k] || p[k] > c->box[k + 3];
            if (out && (uint64_t)(uint32_t)L->in_id[i] < least) {
                least = (uint64_t)(uint32_t)L->in_id[i];
                at = i;
            }
        }
        MPI_Allreduce(&least, &all, 1, MPI_UINT64_T, MPI_MIN, c->comm);
        err = FDT_OK;
        if (all != UINT64_MAX && all == least) /* its one holder says so */
            err = fdt_voronoi_box_of(L->in_xyz + 3 * at, L->in_id + at, 1, &vo, c->box, c->diag,
                                     c->dlen);
        if ((err = agree(c, err)) != FDT_OK)
            return err;
    } else {
        /* each rank's bounding box, as frontdt's rule computes it, then
         * theirs */
        double mine[6];
        (void)fdt_voronoi_box_of(L->in_xyz, NULL, L->nin, &vo, mine, NULL, 0);
        MPI_Allreduce(mine, c->box, 3, MPI_DOUBLE, MPI_MIN, c->comm);
        MPI_Allreduce(mine + 3, c->box + 3, 3, MPI_DOUBLE, MPI_MAX, c->comm);
    }
    /* the same box on every rank, so the same answer */
    return fdt_voronoi_scale(c->box, &c->ed, c->diag, c->dlen);
}

/* ---- 2. the stars to the owners of their vertices ------------------------ */

typedef struct prec {
    uint64_t id;
    double x[3];
} prec;

/* A received point's input id and its position among those received. */
typedef struct idpos {
    uint64_t id, at;
} idpos;

static int idpos_cmp(const void *x, const void *y)
{
    const idpos *a = x, *b = y;
    return a->id < b->id ? -1 : a->id > b->id ? 1 : a->at < b->at ? -1 : a->at > b->at;
}

/* The index of input id v among the ascending ids[0 .. n), or n. */
static size_t find_id(const fdt_vid *ids, size_t n, fdt_vid v)
{
    size_t a = 0, b = n;
    while (a < b) {
        size_t m = a + (b - a) / 2;
        if (ids[m] < v)
            a = m + 1;
        else
            b = m;
    }
    return a < n && ids[a] == v ? a : n;
}

/* The ranks owning the vertices of tet t (4 input ids), distinct, into
 * d; their count. */
static int owners(const cells_run *c, const fdt_vid *t, int d[4])
{
    int k = 0;
    for (int j = 0; j < 4; j++) {
        int q = fdt_mpi_block_owner(c->L->n, c->size, (uint64_t)(uint32_t)t[j]);
        int seen = 0;
        for (int i = 0; i < k; i++)
            seen |= d[i] == q;
        if (!seen)
            d[k++] = q;
    }
    return k;
}

/*
 * Every tet this rank built goes to each rank owning one of its vertices,
 * with the points it uses: to each destination a list of points (input
 * id and coordinates, each once) and the tets as four positions in that
 * list: 32 bytes a point and 16 a tet, instead of 112 a tet with its
 * coordinates. The receiver merges the lists of its sources by input id.
 * MPI counts are ints: more than INT_MAX records to send is FDT_ETOOBIG.
 */
static int send_stars(cells_run *c)
{
    const fdt_mpi_out *r = c->r;
    size_t nt = r->own_ntets, np = r->own_npts;
    int size = c->size;
    int *cnt = calloc(8 * (size_t)size, sizeof *cnt);
    uint32_t *tv = malloc((4 * nt + 1) * sizeof *tv);     /* each vertex's point */
    uint32_t *pos = malloc((np + 1) * sizeof *pos);       /* its position, one dest */
    /* each vertex's point: a hash table of own_ids (a binary search a
     * vertex was a third of this step on 1M points) */
    size_t cap = 16;
    while (cap < 2 * np)
        cap *= 2;
    uint64_t *tab = malloc(cap * sizeof *tab); /* (id + 1) << 32 | index; 0 empty */
    uint32_t *byd = NULL, (*ts)[4] = NULL, *plist = NULL, (*rt)[4] = NULL, *map = NULL;
    prec *ps = NULL, *rp = NULL;
    size_t npairs = 0, nps = 0;
    int err = cnt && tv && pos && tab ? FDT_OK : oom(c, "sending the stars");
    if (!err) {
        memset(tab, 0, cap * sizeof *tab);
        for (size_t i = 0; i < np; i++) {
            uint64_t key = (uint64_t)(uint32_t)r->own_ids[i] + 1;
            size_t h = (size_t)((key * 0x9E3779B97F4A7C15ull) >> 40) & (cap - 1);
            while (tab[h])
                h = (h + 1) & (cap - 1);
            tab[h] = key << 32 | i;
        }
    }
    for (size_t i = 0; !err && i < 4 * nt; i++) {
        uint64_t key = (uint64_t)(uint32_t)r->own_tets[i] + 1;
        size_t h = (size_t)((key * 0x9E3779B97F4A7C15ull) >> 40) & (cap - 1);
        while (tab[h] && tab[h] >> 32 != key)
            h = (h + 1) & (cap - 1);
        if (!tab[h]) {
            snprintf(c->diag, c->dlen, "a tet's vertex %d has no coordinates",
                     (int)r->own_tets[i]);
            err = FDT_EINTERNAL;
        }
        tv[i] = (uint32_t)tab[h];
    }
    free(tab);
    if ((err = agree(c, err)) != FDT_OK)
        goto done;
    /* exchange()'s rows: the tets', then the points' */
    int *tc = cnt, *td = cnt + size, *trc = cnt + 2 * size, *trd = cnt + 3 * size;
    int *pc = cnt + 4 * size, *prc = cnt + 6 * size, *prd = cnt + 7 * size;
    /* the (destination, tet) pairs, grouped by destination */
    int d[4];
    for (size_t t = 0; t < nt; t++)
        for (int k = owners(c, r->own_tets + 4 * t, d); k-- > 0;)
            tc[d[k]]++, npairs++;
    if (npairs > INT_MAX) {
        snprintf(c->diag, c->dlen, "too many tets on one rank for MPI's int counts");
        err = FDT_ETOOBIG;
    }
    byd = err ? NULL : malloc((npairs + 1) * sizeof *byd);
    ts = err ? NULL : malloc((npairs + 1) * sizeof *ts);
    size_t pcap = np + 1; /* a point once a destination: grown below */
    plist = err ? NULL : malloc(pcap * sizeof *plist);
    if (!err && !(byd && ts && plist))
        err = oom(c, "sending the stars");
    if ((err = agree(c, err)) != FDT_OK)
        goto done;
    starts(tc, td, size);
    for (size_t t = 0; t < nt; t++)
        for (int k = owners(c, r->own_tets + 4 * t, d); k-- > 0;)
            byd[td[d[k]]++] = (uint32_t)t;
    starts(tc, td, size); /* moved on by the fill: back */
    /* each destination's point list and its tets' positions in it */
    for (size_t i = 0; i < np; i++)
        pos[i] = UINT32_MAX;
    for (int q = 0; q < size && !err; q++) {
        size_t first = nps;
        for (int i = td[q]; i < td[q] + tc[q] && !err; i++) {
            const uint32_t *v = tv + 4 * (size_t)byd[i];
            for (int j = 0; j < 4; j++) {
                if (pos[v[j]] == UINT32_MAX) {
                    if (nps == pcap && fdt_grow(&plist, &pcap, nps + 1, sizeof *plist)) {
                        err = FDT_ENOMEM;
                        break;
                    }
                    pos[v[j]] = (uint32_t)(nps - first);
                    plist[nps++] = v[j];
                }
                ts[i][j] = pos[v[j]];
            }
        }
        pc[q] = (int)(nps - first);
        for (size_t i = first; i < nps; i++)
            pos[plist[i]] = UINT32_MAX;
    }
    if (!err && nps > INT_MAX) {
        snprintf(c->diag, c->dlen, "too many points on one rank for MPI's int counts");
        err = FDT_ETOOBIG;
    }
    ps = err ? NULL : malloc((nps + 1) * sizeof *ps);
    if (err == FDT_ENOMEM || (!err && !ps))
        err = oom(c, "sending the stars");
    if ((err = agree(c, err)) != FDT_OK)
        goto done;
    for (size_t i = 0; i < nps; i++) {
        ps[i].id = (uint64_t)(uint32_t)r->own_ids[plist[i]];
        memcpy(ps[i].x, r->own_xyz + 3 * (size_t)plist[i], sizeof ps[i].x);
    }
    size_t nrt = 0, nrp = 0;
    if ((err = exchange(c, ts, tc, sizeof *ts, (void **)&rt, &nrt, "receiving the stars")) !=
            FDT_OK ||
        (err = exchange(c, ps, pc, sizeof *ps, (void **)&rp, &nrp, "receiving the stars")) !=
            FDT_OK)
        goto done;
    free(ts);
    ts = NULL;
    free(ps);
    ps = NULL;
    /* the sources' lists merged by input id: map[i], the distinct point
     * of received point i */
    map = malloc((nrp + 1) * sizeof *map);
    idpos *sorted = malloc((nrp + 1) * sizeof *sorted);
    c->ids = malloc((nrp + 1) * sizeof *c->ids);
    c->xyz = malloc((3 * nrp + 1) * sizeof *c->xyz);
    c->tets = malloc((4 * nrt + 1) * sizeof *c->tets);
    err = map && sorted && c->ids && c->xyz && c->tets ? FDT_OK : oom(c, "receiving the stars");
    if (!err) {
        for (size_t i = 0; i < nrp; i++) {
            sorted[i].id = rp[i].id;
            sorted[i].at = i;
        }
        qsort(sorted, nrp, sizeof *sorted, idpos_cmp);
        size_t u = 0;
        for (size_t i = 0; i < nrp; i++) {
            size_t at = (size_t)sorted[i].at;
            if (i == 0 || sorted[i].id != sorted[i - 1].id) {
                c->ids[u] = (fdt_vid)sorted[i].id;
                memcpy(c->xyz + 3 * u, rp[at].x, sizeof rp[at].x);
                u++;
            }
            map[at] = (uint32_t)(u - 1);
        }
        c->npts = u;
        /* the tets' positions, each relative to its source's list */
        for (int q = 0; q < size && !err; q++)
            for (int i = trd[q]; i < trd[q] + trc[q]; i++)
                for (int j = 0; j < 4; j++) {
                    if (rt[i][j] >= (uint32_t)prc[q]) {
                        snprintf(c->diag, c->dlen, "a star's tet from rank %d names a point "
                                 "it did not send", q);
                        err = FDT_EINTERNAL;
                        break;
                    }
                    c->tets[4 * (size_t)i + j] = map[(size_t)prd[q] + rt[i][j]];
                }
        c->ntets = nrt;
    }
    free(sorted);
    err = agree(c, err);
done:
    free(cnt);
    free(tv);
    free(pos);
    free(byd);
    free(ts);
    free(plist);
    free(ps);
    free(rt);
    free(rp);
    free(map);
    return err;
}

/* ---- 3. the hull's vertices to their owners ------------------------------ */

static int send_hull(cells_run *c)
{
    const fdt_mpi_out *r = c->r;
    size_t nh = 3 * r->own_nhull;
    int size = c->size;
    int *cnt = calloc(4 * (size_t)size, sizeof *cnt);
    uint32_t *sb = malloc((nh + 1) * sizeof *sb), *rb = NULL;
    c->hull = calloc(c->npts + 1, 1);
    int err = cnt && sb && c->hull ? FDT_OK : oom(c, "sending the hull");
    if ((err = agree(c, err)) != FDT_OK)
        goto done;
    int *sc = cnt, *sd = cnt + size; /* exchange()'s first two rows */
    for (size_t i = 0; i < nh; i++)
        sc[fdt_mpi_block_owner(c->L->n, size, (uint64_t)(uint32_t)r->own_hull[i])]++;
    starts(sc, sd, size);
    for (size_t i = 0; i < nh; i++)
        sb[sd[fdt_mpi_block_owner(c->L->n, size, (uint64_t)(uint32_t)r->own_hull[i])]++] =
            (uint32_t)r->own_hull[i];
    size_t nr = 0;
    if ((err = exchange(c, sb, sc, sizeof *sb, (void **)&rb, &nr, "receiving the hull")) != FDT_OK)
        goto done;
    for (size_t i = 0; i < nr && !err; i++) {
        size_t k = find_id(c->ids, c->npts, (fdt_vid)rb[i]);
        if (k == c->npts) {
            snprintf(c->diag, c->dlen, "hull vertex %" PRIu32 " has no star", rb[i]);
            err = FDT_EINTERNAL;
        } else {
            c->hull[k] = 1;
        }
    }
    err = agree(c, err);
done:
    free(cnt);
    free(sb);
    free(rb);
    return err;
}

/* ---- 4. the block's input points ------------------------------------------ */

typedef struct irec {
    uint64_t id, vertex;
    double x[3];
} irec;

/* Each input point (duplicates included) to the owner of its id: the
 * vertex it was merged into and its coordinates, by id. */
static int send_inputs(cells_run *c)
{
    const fdt_mpi_local *L = c->L;
    int size = c->size;
    int *cnt = calloc(4 * (size_t)size, sizeof *cnt);
    irec *sb = malloc((L->nin + 1) * sizeof *sb), *rb = NULL;
    unsigned char *seen = calloc(c->nmine + 1, 1);
    c->vertex = malloc((c->nmine + 1) * sizeof *c->vertex);
    c->pts = malloc((3 * c->nmine + 1) * sizeof *c->pts);
    int err = cnt && sb && seen && c->vertex && c->pts ? FDT_OK : oom(c, "sending the points");
    if ((err = agree(c, err)) != FDT_OK)
        goto done;
    int *sc = cnt, *sd = cnt + size; /* exchange()'s first two rows */
    for (size_t i = 0; i < L->nin; i++)
        sc[fdt_mpi_block_owner(L->n, size, (uint64_t)(uint32_t)L->in_id[i])]++;
    starts(sc, sd, size);
    for (size_t i = 0; i < L->nin; i++) {
        irec *p = &sb[sd[fdt_mpi_block_owner(L->n, size, (uint64_t)(uint32_t)L->in_id[i])]++];
        p->id = (uint64_t)(uint32_t)L->in_id[i];
        p->vertex = (uint64_t)(uint32_t)L->in_vertex[i];
        memcpy(p->x, L->in_xyz + 3 * i, sizeof p->x);
    }
    size_t nr = 0;
    if ((err = exchange(c, sb, sc, sizeof *sb, (void **)&rb, &nr, "receiving the points")) !=
        FDT_OK)
        goto done;
    for (size_t i = 0; i < nr && !err; i++) {
        size_t j = (size_t)(rb[i].id - c->lo);
        if (rb[i].id < c->lo || j >= c->nmine || seen[j]) {
            snprintf(c->diag, c->dlen, "input id %" PRIu64 " twice or outside its block",
                     rb[i].id);
            err = FDT_EINTERNAL;
            break;
        }
        seen[j] = 1;
        c->vertex[j] = (fdt_vid)rb[i].vertex;
        memcpy(c->pts + 3 * j, rb[i].x, sizeof rb[i].x);
    }
    if (!err && nr != c->nmine) {
        snprintf(c->diag, c->dlen, "input points lost on their way to their block");
        err = FDT_EINTERNAL;
    }
    err = agree(c, err);
done:
    free(cnt);
    free(sb);
    free(rb);
    free(seen);
    return err;
}

/* ---- 5. the block's cells --------------------------------------------------- */

/* The least of the ranks' too-short edges (fdt_edge_less), to every rank:
 * whether there is one. */
static int least_short(cells_run *c, fdt_vshort *sh)
{
    double mine[3] = {(double)sh->a, (double)sh->b, sh->len};
    double *all = malloc(3 * (size_t)c->size * sizeof *all);
    int ok = all != NULL, allok = 0;
    MPI_Allreduce(&ok, &allok, 1, MPI_INT, MPI_MIN, c->comm);
    if (!allok) {
        free(all);
        return -1;
    }
    MPI_Allgather(mine, 3, MPI_DOUBLE, all, 3, MPI_DOUBLE, c->comm);
    fdt_vshort best = {-1, -1, 0};
    for (int q = 0; q < c->size; q++) {
        long long a = (long long)all[3 * q], b = (long long)all[3 * q + 1];
        if (a >= 0 && (best.a < 0 || fdt_edge_less(a, b, best.a, best.b))) {
            best.a = a;
            best.b = b;
            best.len = all[3 * q + 2];
        }
    }
    free(all);
    *sh = best;
    return best.a >= 0;
}

static int block_cells(cells_run *c)
{
    uint32_t *own = malloc((c->nmine + 1) * sizeof *own);
    uint8_t *own_hull = malloc(c->nmine + 1), *skip = malloc(c->npts + 1);
    fdt_vid *dup_ids = malloc((c->nmine + 1) * sizeof *dup_ids);
    double *dup_pts = malloc((3 * c->nmine + 1) * sizeof *dup_pts);
    int err = own && own_hull && skip && dup_ids && dup_pts ? FDT_OK : oom(c, "for the cells");
    size_t nown = 0, ndup = 0;
    /* the block's vertices, each with its star (the distinct points are
     * by id: the block's are consecutive), and its duplicates */
    size_t k = 0;
    while (!err && k < c->npts && (size_t)(uint32_t)c->ids[k] < c->lo)
        k++;
    if (!err)
        memset(skip, 1, c->npts);
    for (size_t j = 0; !err && j < c->nmine; j++) {
        fdt_vid id = (fdt_vid)(c->lo + j);
        if (c->vertex[j] != id) {
            dup_ids[ndup] = id;
            memcpy(dup_pts + 3 * ndup++, c->pts + 3 * j, 3 * sizeof *dup_pts);
        } else if (k < c->npts && c->ids[k] == id) {
            skip[k++] = 0;
            nown++;
        } else {
            snprintf(c->diag, c->dlen, "point %d's star never came", (int)id);
            err = FDT_EINTERNAL;
        }
    }
    /* in Morton order, as fdt_voronoi_compute numbers its points: the
     * batch numbers them in this order, and its tet and cell passes then
     * read neighbouring points (input order: 3x slower on 1M uniform
     * points) */
    if (!err && fdt_morton_order(c->xyz, c->npts, c->box, skip, own) != (long)nown)
        err = oom(c, "for the cells");
    for (size_t i = 0; !err && i < nown; i++)
        own_hull[i] = c->hull[own[i]];
    if ((err = agree(c, err)) != FDT_OK)
        goto done;
    fdt_vbatch b = {c->xyz, 0, c->ids, own, nown, own_hull, c->tets, c->ntets, NULL,
                    {0}, c->ed, c->o->neighbors, c->o->skip, 0};
    memcpy(b.box, c->box, sizeof b.box);
    fdt_vshort sh = {-1, -1, 0};
    err = fdt_voronoi_batch(&b, 1, &c->cells, &sh, c->diag, c->dlen);
    int short_edge = err == FDT_ERANGE && sh.a >= 0;
    if (short_edge)
        err = FDT_OK; /* the least edge of all ranks decides, below */
    if (!err && !short_edge &&
        (err = fdt_voronoi_merged(dup_ids, dup_pts, ndup, c->box, c->o->neighbors, c->o->skip,
                                  &c->merged)) != FDT_OK)
        oom(c, "for the cells");
    if ((err = agree(c, err)) != FDT_OK)
        goto done;
    int any = least_short(c, &sh);
    if (any < 0)
        err = agree(c, oom(c, "for the cells"));
    else if (any)
        err = fdt_voronoi_too_close(&sh, c->box, c->diag, c->dlen);
done:
    free(own);
    free(own_hull);
    free(skip);
    free(dup_ids);
    free(dup_pts);
    return err;
}

/* ---- 6. the tables ---------------------------------------------------------- */

/* A table of the block's spool: fdt_mpo_text's writer. */
typedef struct spooled {
    fdt_cells_spool *sp;
    int table, header;
} spooled;

static int put_spooled(void *user, FILE *f)
{
    const spooled *t = user;
    return fdt_cells_spool_put(t->sp, t->table, t->header, f);
}

/* One table (0 the cells', 1 the densities) at path: each rank's block's
 * rows from its spool straight into the file, at its offset. */
static int write_table(cells_run *c, fdt_cells_spool *sp, int table, const char *path)
{
    spooled t = {sp, table, c->rank == 0};
    return fdt_mpo_text(c->comm, path, put_spooled, &t,
                        fdt_cells_spool_bytes(sp, table, t.header), &c->written, c->diag,
                        c->dlen);
}

static int write_tables(cells_run *c)
{
    const fdt_mpi_cells_opts *o = c->o;
    fdt_cells_spool *sp = NULL;
    char dir[4200];
    fdt_cells_dir(o->voronoi ? o->voronoi : o->density, dir, sizeof dir);
    int e = fdt_cells_spool_open(&sp, c->lo, c->nmine, o->voronoi ? o->format : NULL,
                                 o->voronoi && !o->format, o->density != NULL, dir);
    if (!e)
        e = fdt_cells_spool_add(sp, c->cells);
    if (!e)
        e = fdt_cells_spool_add(sp, c->merged);
    int err = FDT_OK;
    if (e) {
        snprintf(c->diag, c->dlen, "%s: a temporary file for the cells: %s", dir, strerror(e));
        err = e == ENOMEM ? FDT_ENOMEM : FDT_EIO;
    }
    if ((err = agree(c, err)) == FDT_OK && o->voronoi)
        err = write_table(c, sp, 0, o->voronoi);
    if (!err && o->density)
        err = write_table(c, sp, 1, o->density);
    fdt_cells_spool_close(&sp);
    return err;
}

/* ---- the steps ---------------------------------------------------------------- */

int fdt_mpi_cells(MPI_Comm comm, const fdt_mpi_local *L, const fdt_mpi_out *r,
                  const fdt_mpi_cells_opts *o, fdt_mpi_cells_stats *st, char *diag, size_t dlen)
{
    double t0 = fdt_now_s();
    cells_run c;
    memset(&c, 0, sizeof c);
    c.comm = comm;
    MPI_Comm_rank(comm, &c.rank);
    MPI_Comm_size(comm, &c.size);
    c.L = L;
    c.r = r;
    c.o = o;
    c.diag = diag;
    c.dlen = dlen;
    diag[0] = '\0';
    c.lo = fdt_mpi_block_start(L->n, c.size, c.rank);
    c.nmine = fdt_mpi_block_start(L->n, c.size, c.rank + 1) - c.lo;
    int err = the_box(&c);
    if (!err)
        err = send_stars(&c);
    if (!err)
        err = send_hull(&c);
    if (!err)
        err = send_inputs(&c);
    if (!err)
        err = block_cells(&c);
    if (!err)
        err = write_tables(&c);
    st->t = fdt_now_s() - t0;
    st->star_tets = c.ntets;
    st->bytes_sent = c.bytes;
    st->bytes_written = c.written;
    fdt_voronoi_free(&c.cells);
    fdt_voronoi_free(&c.merged);
    free(c.ids);
    free(c.xyz);
    free(c.tets);
    free(c.hull);
    free(c.vertex);
    free(c.pts);
    return err;
}
