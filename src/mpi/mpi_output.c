/*
 * The distributed output of frontdt-mpi (src/mpi/mpi_output.h; issue 19): one
 * piece a rank, in input numbering, and an index by rank 0; the .node of
 * a .pele written by every rank into one file. No rank ever holds more
 * than its own tets and a 1/p share of the points.
 */
#include "mpi/mpi_output.h"

#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "io/write/formats.h"
#include "io/write/outfile.h"
#include "base/sethash.h"
#include "io/write/writer.h"
#include "mesh/periodic.h"

/* ---- names ---------------------------------------------------------------- */

static const char *const index_ext[] = {NULL, ".pvtu", ".pfdtb", ".pele"};
static const char *const piece_ext[] = {NULL, ".vtu", ".fdtb", ".ele"};
static const char *const format_word[] = {NULL, "vtu", "fdtb", "ele"};

int fdt_mpo_kind(const char *path)
{
    size_t n = strlen(path);
    for (int k = FDT_MPO_VTU; k <= FDT_MPO_ELE; k++) {
        size_t e = strlen(index_ext[k]);
        if (n > e && strcasecmp(path + n - e, index_ext[k]) == 0)
            return k;
    }
    return FDT_MPO_GATHER;
}

/* BASE + mid + ext beside the index path (BASE: path less its extension).
 * 0, or -1 if it does not fit. */
static int sibling(const char *path, int kind, const char *mid, const char *ext, char *out,
                   size_t len)
{
    size_t n = strlen(path) - strlen(index_ext[kind]);
    int k = snprintf(out, len, "%.*s%s%s", (int)n, path, mid, ext);
    return k < 0 || (size_t)k >= len ? -1 : 0;
}

/* A rank's piece: .vtu, .fdtb or .ele (face: its .face beside it). */
static int piece_name(const char *path, int kind, int rank, int face, char *out, size_t len)
{
    char mid[24];
    snprintf(mid, sizeof mid, "_%d", rank);
    return sibling(path, kind, mid, face ? ".face" : piece_ext[kind], out, len);
}

int fdt_mpo_file(const char *path, int size, size_t k, char *out, size_t len)
{
    int kind = fdt_mpo_kind(path);
    if (kind == FDT_MPO_GATHER)
        return 0;
    int rc;
    if (k < (size_t)size)
        rc = piece_name(path, kind, (int)k, 0, out, len);
    else if (kind != FDT_MPO_ELE)
        return 0;
    else if (k < 2 * (size_t)size)
        rc = piece_name(path, kind, (int)(k - (size_t)size), 1, out, len);
    else if (k == 2 * (size_t)size)
        rc = sibling(path, kind, "", ".node", out, len);
    else
        return 0;
    return rc ? -1 : 1;
}

/* The name relative to the index's directory. */
static const char *rel_name(const char *name)
{
    const char *slash = strrchr(name, '/');
    return slash ? slash + 1 : name;
}

/* ---- signal cleanup --------------------------------------------------------
 *
 * From the moment a rank starts its piece until every rank has passed the
 * barrier after the index (complete) or after the removals (failed), an
 * interrupt removes this rank's pieces, the .node and the index (any rank
 * may: they name the same files), so an index never outlives a file it
 * names and nothing partial is left: the writer's registry of temporaries
 * guards them (fdt_io_guard, src/io/write/writer.h), and its signal
 * cleanup (fdt_write_cleanup) removes them. At most four names, beside the
 * writer's own temporaries of this rank (three at a time): the registry's
 * 32 slots always have room. */
enum { GUARD_MAX = 4 };

static void guard_all(char (*names)[FDT_IO_PATH], int n, int *slot)
{
    fdt_write_lock();
    for (int i = 0; i < n; i++)
        slot[i] = fdt_io_guard(names[i]);
    fdt_write_unlock();
}

static void unguard_all(const int *slot, int n)
{
    fdt_write_lock();
    for (int i = 0; i < n; i++)
        fdt_io_unguard(slot[i]);
    fdt_write_unlock();
}

/* ---- pieces ---------------------------------------------------------------- */

static int io_code(int io)
{
    return io == FDT_IO_OK ? FDT_OK : io == FDT_IO_ENOMEM ? FDT_ENOMEM : FDT_EIO;
}

/* .vtu: the rank's tets over the points they use (ids: their input ids,
 * ascending; xyz their coordinates), renumbered 0..npts-1 in that order. */
static int write_vtu(const char *name, const fdt_mpi_out *r, char *diag, size_t dlen)
{
    size_t nt = r->own_ntets, npts = r->own_npts;
    const fdt_vid *ids = r->own_ids, *tets = r->own_tets;
    fdt_vid *lt = malloc((4 * nt + 1) * sizeof *lt);
    if (!lt) {
        snprintf(diag, dlen, "out of memory writing a piece");
        return FDT_ENOMEM;
    }
    for (size_t i = 0; i < 4 * nt; i++) {
        /* ids is sorted and holds every id the tets use */
        size_t lo = 0, hi = npts;
        while (hi - lo > 1) {
            size_t mid = lo + (hi - lo) / 2;
            if (ids[mid] <= tets[i])
                lo = mid;
            else
                hi = mid;
        }
        lt[i] = (fdt_vid)lo;
    }
    fdt_mesh_view v;
    memset(&v, 0, sizeof v);
    v.xyz = r->own_xyz;
    v.n_points = npts;
    v.tets = lt;
    v.n_tets = nt;
    int err = io_code(fdt_wr_mesh_as(name, fdt_format_by_name("vtu"), &v, diag, dlen));
    free(lt);
    return err;
}

int fdt_mpo_periodic_vtu(const char *name, const fdt_vid *tets, const int8_t *off, size_t nt,
                         const double *xyz, size_t n, const fdt_periodic_box *b, char *diag,
                         size_t dlen)
{
    /* laid out without the hull faces (a .vtu has none; a piece's hull
     * faces may lie on another piece's tets), then only the points its
     * tets use, in the order laid out (the input points, then images) */
    fdt_periodic_unfolded u;
    int err = fdt_periodic_unfold((const int32_t *)tets, off, nt, NULL, NULL, 0, xyz, n, b, &u);
    uint32_t *at = NULL;
    double *px = NULL;
    fdt_vid *src = NULL;
    int8_t *po = NULL;
    if (!err) {
        at = malloc((u.n + 1) * sizeof *at);
        px = malloc((3 * u.n + 1) * sizeof *px);
        src = malloc((u.n + 1) * sizeof *src);
        po = malloc(3 * u.n + 1);
        if (!at || !px || !src || !po)
            err = FDT_ENOMEM;
    }
    if (err) {
        snprintf(diag, dlen, "%s: %s", name, fdt_strerror(err));
    } else {
        for (size_t i = 0; i < u.n; i++)
            at[i] = UINT32_MAX;
        for (size_t i = 0; i < 4 * u.ntets; i++)
            at[u.tets[i]] = 0;
        size_t m = 0;
        for (size_t i = 0; i < u.n; i++)
            if (at[i] == 0) {
                at[i] = (uint32_t)m;
                memcpy(px + 3 * m, u.xyz + 3 * i, 3 * sizeof *px);
                memcpy(po + 3 * m, u.off + 3 * i, 3);
                src[m++] = u.src[i];
            }
        for (size_t i = 0; i < 4 * u.ntets; i++)
            u.tets[i] = (fdt_vid)at[u.tets[i]];
        fdt_mesh_view v;
        memset(&v, 0, sizeof v);
        v.xyz = px;
        v.n_points = m;
        v.tets = u.tets;
        v.n_tets = u.ntets;
        v.point_src = src;
        v.point_off = po;
        err = io_code(fdt_wr_mesh_as(name, fdt_format_by_name("vtu"), &v, diag, dlen));
    }
    free(at);
    free(px);
    free(src);
    free(po);
    fdt_periodic_unfolded_free(&u);
    return err;
}

int fdt_mpo_bin_piece(const char *name, uint64_t n_input, const fdt_vid *tets, size_t nt,
                      const fdt_vid *hull, size_t nh, const fdt_bin_periodic *per, char *diag,
                      size_t dlen)
{
    out_file f;
    fdt_write_lock();
    int e = fdt_out_open(&f, name);
    fdt_write_unlock();
    if (e)
        return io_code(fdt_create_err(diag, dlen, "output", name, e));
    fdt_put_bin_piece(&f, n_input, tets, nt, hull, nh, per);
    fdt_write_lock();
    int rc = io_code(fdt_out_commit(&f, 1, diag, dlen));
    fdt_write_unlock();
    return rc;
}

/* A .pele piece: opens the .ele's and the .face's temporaries, puts them,
 * commits both or none (src/io/write/writer.c). */
static int write_ele(char (*names)[FDT_IO_PATH], int k, uint64_t n_input, const fdt_mpi_out *r,
                     char *diag, size_t dlen)
{
    out_file f[2];
    int nopen = 0, e = 0;
    fdt_write_lock();
    for (; nopen < k && !e; nopen++)
        if ((e = fdt_out_open(&f[nopen], names[nopen])) != 0)
            break;
    fdt_write_unlock();
    if (e) {
        int code = io_code(fdt_create_err(diag, dlen, "output", names[nopen], e));
        fdt_write_lock();
        for (int i = 0; i < nopen; i++)
            fdt_out_abandon(&f[i]);
        fdt_write_unlock();
        return code;
    }
    fdt_mesh_view v;
    memset(&v, 0, sizeof v);
    v.n_points = n_input;
    v.tets = r->own_tets;
    v.n_tets = r->own_ntets;
    v.hull = r->own_hull;
    v.n_hull = r->own_nhull;
    fdt_put_tetgen_ele(&f[0], &v, NULL, diag, dlen);
    fdt_put_tetgen_face(&f[1], &v, NULL, diag, dlen);
    fdt_write_lock();
    int rc = io_code(fdt_out_commit(f, k, diag, dlen));
    fdt_write_unlock();
    return rc;
}

/* ---- the collective .node -------------------------------------------------
 *
 * The serial .node is "N 3 0 0" and then a line "ID X Y Z" an input point
 * in input order, the coordinates as read in %.17g (src/io/write/fmt_tetgen.c).
 * Rank q takes the input ids [N q/p, N (q+1)/p): every rank sends each of
 * its points (the setup's in_id/in_xyz, duplicates included) to the rank
 * of its id (one MPI_Alltoallv of 32 bytes a point), formats its lines
 * exactly as the serial writer does, and an MPI_Exscan of the byte counts
 * gives each rank its offset; fdt_mpo_text writes them into rank 0's
 * temporary (src/io/write/writer.c, so the rename and the signal cleanup
 * are the usual ones), each rank at its offset, and rank 0 commits only
 * after all have: the renamed file is complete, or nothing is renamed. */
typedef struct nrec {
    double x[3];
    uint64_t id;
} nrec;

int fdt_mpo_text(MPI_Comm comm, const char *name, int (*put)(void *, FILE *), void *user,
                 uint64_t len, uint64_t *io, char *diag, size_t dlen)
{
    int rank;
    MPI_Comm_rank(comm, &rank);
    int err = FDT_OK;
    out_file of;
    int of_open = 0;
    uint64_t off = 0;
    MPI_Exscan(&len, &off, 1, MPI_UINT64_T, MPI_SUM, comm);
    if (rank == 0)
        off = 0; /* MPI_Exscan leaves rank 0's undefined */
    /* rank 0's temporary, its path to every rank */
    char tpath[FDT_IO_PATH] = "";
    if (rank == 0) {
        fdt_write_lock();
        int e = fdt_out_open(&of, name);
        fdt_write_unlock();
        if (e)
            err = io_code(fdt_create_err(diag, dlen, "output", name, e));
        else {
            of_open = 1;
            snprintf(tpath, sizeof tpath, "%s", fdt_out_temp(&of));
        }
    }
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK)
        goto done;
    MPI_Bcast(tpath, (int)sizeof tpath, MPI_CHAR, 0, comm);
    /* Every rank, rank 0 too, writes its bytes at its offset through a
     * stream of its own on the temporary (rank 0's out_file stays empty
     * until the commit); no O_CREAT: if rank 0's temporary is gone (an
     * interrupt), fail. Exactly len bytes, or the offsets would not add
     * up. */
    int fd = open(tpath, O_WRONLY | O_CLOEXEC);
    FILE *f = fd < 0 ? NULL : fdopen(fd, "wb"); /* no truncation: the fd is open */
    int e = !f ? errno : 0;
    if (!f && fd >= 0)
        close(fd);
    errno = 0;
    if (!e && fseeko(f, (off_t)off, SEEK_SET) != 0)
        e = errno ? errno : EIO;
    if (!e)
        e = put(user, f);
    if (!e && fflush(f) != 0)
        e = errno ? errno : EIO;
    if (!e && (uint64_t)ftello(f) != off + len)
        e = EIO;
    if (f && fclose(f) != 0 && !e)
        e = errno ? errno : EIO;
    if (e)
        err = io_code(set_errno_err(diag, dlen, name, e));
    io[0] += len;
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) == FDT_OK && rank == 0) {
        fdt_write_lock();
        err = io_code(fdt_out_commit(&of, 1, diag, dlen));
        fdt_write_unlock();
        of_open = 0;
    }
    err = fdt_mpi_agree(comm, err, diag, dlen);
done:
    if (of_open) {
        fdt_write_lock();
        fdt_out_abandon(&of);
        fdt_write_unlock();
    }
    return err;
}

/* A text in memory: fdt_mpo_text's writer. */
typedef struct mem_text {
    const char *p;
    size_t len;
} mem_text;

static int put_mem(void *user, FILE *f)
{
    const mem_text *t = user;
    errno = 0;
    return fwrite(t->p, 1, t->len, f) == t->len ? 0 : errno ? errno : EIO;
}

static int write_node(MPI_Comm comm, const char *name, const fdt_mpi_local *L, uint64_t *io,
                      char *diag, size_t dlen)
{
    int rank, size;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    uint64_t n = L->n;
    size_t lo = fdt_mpi_block_start(n, size, rank), nmine = fdt_mpi_block_start(n, size, rank + 1) - lo;
    int *c = malloc(4 * (size_t)size * sizeof *c);
    nrec *sb = malloc((L->nin + 1) * sizeof *sb), *rb = malloc((nmine + 1) * sizeof *rb);
    char *text = malloc(nmine * 100 + 64);
    int err = c && sb && rb && text ? FDT_OK : FDT_ENOMEM;
    snprintf(diag, dlen, "out of memory writing %s", name);
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK)
        goto done;
    int *sc = c, *sd = c + size, *rc = c + 2 * size, *rd = c + 3 * size;
    memset(sc, 0, (size_t)size * sizeof *sc);
    for (size_t i = 0; i < L->nin; i++)
        sc[fdt_mpi_block_owner(n, size, (uint64_t)(uint32_t)L->in_id[i])]++;
    size_t nr = fdt_mpi_counts(comm, sc, sd, rc, rd, sizeof(nrec), &io[1]);
    /* counting sort by destination (sd[] moves on; put back below) */
    for (size_t i = 0; i < L->nin; i++) {
        int q = fdt_mpi_block_owner(n, size, (uint64_t)(uint32_t)L->in_id[i]);
        nrec *p = &sb[sd[q]++];
        memcpy(p->x, L->in_xyz + 3 * i, sizeof p->x);
        p->id = (uint64_t)(uint32_t)L->in_id[i];
    }
    for (int q = 0; q < size; q++)
        sd[q] -= sc[q];
    MPI_Datatype nt;
    MPI_Type_contiguous((int)sizeof(nrec), MPI_BYTE, &nt);
    MPI_Type_commit(&nt);
    nrec *tmp = malloc((nr + 1) * sizeof *tmp);
    err = tmp && nr == nmine ? FDT_OK : tmp ? FDT_EINTERNAL : FDT_ENOMEM;
    snprintf(diag, dlen, "%s writing %s", err == FDT_ENOMEM ? "out of memory" : "points lost",
             name);
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) == FDT_OK)
        MPI_Alltoallv(sb, sc, sd, nt, tmp, rc, rd, nt, comm);
    MPI_Type_free(&nt);
    /* each id of the block exactly once (the setup's in_id partition the
     * input), placed by id */
    unsigned char *seen = err ? NULL : calloc(nmine + 1, 1);
    if (!err && !seen)
        err = FDT_ENOMEM;
    for (size_t i = 0; !err && i < nr; i++) {
        size_t j = (size_t)tmp[i].id - lo;
        if (tmp[i].id < lo || j >= nmine || seen[j]) {
            err = FDT_EINTERNAL;
            snprintf(diag, dlen, "input id %" PRIu64 " twice or outside its block writing %s",
                     tmp[i].id, name);
            break;
        }
        seen[j] = 1;
        rb[j] = tmp[i];
    }
    free(tmp);
    free(seen);
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK)
        goto done;
    /* the lines, as src/io/write/fmt_tetgen.c's fdt_put_tetgen_node writes them */
    size_t len = 0;
    if (rank == 0) {
        len += fdt_utoa(text, n);
        memcpy(text + len, " 3 0 0\n", 7);
        len += 7;
    }
    for (size_t i = 0; i < nmine && !err; i++) {
        len += fdt_utoa(text + len, lo + i);
        for (int d = 0; d < 3; d++) {
            text[len++] = ' ';
            len += fdt_dtoa17(text + len, rb[i].x[d]);
        }
        text[len++] = '\n';
    }
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK)
        goto done;
    mem_text mt = {text, len};
    err = fdt_mpo_text(comm, name, put_mem, &mt, len, io, diag, dlen);
done:
    free(c);
    free(sb);
    free(rb);
    free(text);
    return err;
}

/* ---- indexes --------------------------------------------------------------- */

static int little_endian(void)
{
    const uint16_t one = 1;
    unsigned char b;
    memcpy(&b, &one, 1);
    return b == 1;
}

/* s with XML's five special characters escaped, to f. */
static void put_xml(FILE *f, const char *s)
{
    for (; *s; s++)
        switch (*s) {
        case '&': fputs("&amp;", f); break;
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '"': fputs("&quot;", f); break;
        case '\'': fputs("&apos;", f); break;
        default: fputc(*s, f);
        }
}

/* The ParaView index: it reads the pieces it names (and a periodic
 * mesh's input ids, src/io/write/fmt_vtk.c). */
static void put_pvtu(FILE *f, const char *path, int size, int periodic)
{
    fprintf(f, "<?xml version=\"1.0\"?>\n"
               "<VTKFile type=\"PUnstructuredGrid\" version=\"0.1\" byte_order=\"%s\" "
               "header_type=\"UInt64\">\n"
               "  <PUnstructuredGrid GhostLevel=\"0\">\n"
               "%s"
               "    <PPoints>\n"
               "      <PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n"
               "    </PPoints>\n",
            little_endian() ? "LittleEndian" : "BigEndian",
            periodic ? "    <PPointData Scalars=\"input_id\">\n"
                       "      <PDataArray type=\"Int64\" Name=\"input_id\"/>\n"
                       "    </PPointData>\n"
                     : "");
    char name[FDT_IO_PATH];
    for (int q = 0; q < size; q++) {
        piece_name(path, FDT_MPO_VTU, q, 0, name, sizeof name); /* checked by the caller */
        fputs("    <Piece Source=\"", f);
        put_xml(f, rel_name(name));
        fputs("\"/>\n", f);
    }
    fprintf(f, "  </PUnstructuredGrid>\n</VTKFile>\n");
}

/* The text index of .pfdtb and .pele (src/mpi/mpi_output.h, README). A control
 * character in the input's name would break its line: written as '?'. */
static void put_text_index(FILE *f, const fdt_mpo_args *a, int kind, const fdt_mpo_share *sh,
                           int size, const uint64_t *counts)
{
    fprintf(f, "frontdt-pieces 1\nformat %s\ninput ", format_word[kind]);
    for (const char *s = a->input; *s; s++)
        fputc((unsigned char)*s < 32 || *s == 127 ? '?' : *s, f);
    fprintf(f, "\npoints %" PRIu64 "\nduplicates %" PRIu64 "\nranks %d\n", sh->n_input, sh->ndup,
            size);
    char name[FDT_IO_PATH];
    if (kind == FDT_MPO_ELE) {
        sibling(a->path, kind, "", ".node", name, sizeof name);
        fprintf(f, "node %s\n", rel_name(name));
    }
    uint64_t tt = 0, th = 0;
    for (int q = 0; q < size; q++) {
        piece_name(a->path, kind, q, 0, name, sizeof name);
        fprintf(f, "piece %s %" PRIu64 " %" PRIu64 "\n", rel_name(name), counts[2 * q],
                counts[2 * q + 1]);
        tt += counts[2 * q];
        th += counts[2 * q + 1];
    }
    fprintf(f, "total %" PRIu64 " %" PRIu64 "\nset-hash %016" PRIx64 "\n", tt, th,
            fdt_sethash_value(&sh->hash));
}

/* ---- the whole output ------------------------------------------------------ */

/* The plain engine's share (fdt_mpo_write): its pieces from the run's
 * output r, the .node from the setup's L. */
typedef struct plain_share {
    const fdt_mpi_local *L;
    const fdt_mpi_out *r;
    int kind;
} plain_share;

static int plain_piece(void *user, char (*names)[FDT_IO_PATH], int k, char *diag, size_t dlen)
{
    const plain_share *p = user;
    const fdt_mpi_out *r = p->r;
    if (p->kind == FDT_MPO_VTU)
        return write_vtu(names[0], r, diag, dlen);
    if (p->kind == FDT_MPO_BIN)
        return fdt_mpo_bin_piece(names[0], p->L->n, r->own_tets, r->own_ntets, r->own_hull,
                                 r->own_nhull, NULL, diag, dlen);
    return write_ele(names, k, p->L->n, r, diag, dlen);
}

static int plain_node(MPI_Comm comm, const char *name, void *user, uint64_t *io, char *diag,
                      size_t dlen)
{
    return write_node(comm, name, ((const plain_share *)user)->L, io, diag, dlen);
}

int fdt_mpo_write(MPI_Comm comm, const fdt_mpo_args *a, const fdt_mpi_local *L,
                  const fdt_mpi_out *r, int *mine, uint64_t io[2], char *diag, size_t dlen)
{
    plain_share p = {L, r, fdt_mpo_kind(a->path)};
    const fdt_mpo_share s = {L->n,       L->ndup,    r->own_ntets, r->own_nhull, r->hash, 0,
                             plain_piece, plain_node, &p};
    return fdt_mpo_write_share(comm, a, &s, mine, io, diag, dlen);
}

int fdt_mpo_write_share(MPI_Comm comm, const fdt_mpo_args *a, const fdt_mpo_share *s, int *mine,
                        uint64_t io[2], char *diag, size_t dlen)
{
    io[0] = io[1] = 0;
    int rank, size;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    int kind = fdt_mpo_kind(a->path);
    *mine = FDT_OK;
    diag[0] = '\0';
    if (kind == FDT_MPO_ELE && !s->node) {
        snprintf(diag, dlen, "this run writes no .pele pieces");
        *mine = FDT_EINVAL;
        return FDT_EINVAL; /* the same answer on every rank, nothing written */
    }
    /* The names: this rank's piece (and .face), the .node, the index. The
     * CLI checked every name fits (fdt_mpo_file). */
    char names[2][FDT_IO_PATH], node[FDT_IO_PATH] = "";
    int k = kind == FDT_MPO_ELE ? 2 : 1;
    for (int i = 0; i < k; i++)
        piece_name(a->path, kind, rank, i, names[i], sizeof names[i]);
    if (kind == FDT_MPO_ELE)
        sibling(a->path, kind, "", ".node", node, sizeof node);
    char guarded[GUARD_MAX][FDT_IO_PATH];
    int nl = 0, slot[GUARD_MAX];
    for (int i = 0; i < k; i++)
        memcpy(guarded[nl++], names[i], FDT_IO_PATH);
    if (node[0])
        memcpy(guarded[nl++], node, FDT_IO_PATH);
    snprintf(guarded[nl++], FDT_IO_PATH, "%s", a->path);
    guard_all(guarded, nl, slot); /* from here an interrupt removes them */

    int err = FDT_OK;
    if (kind == FDT_MPO_ELE) {
        err = s->node(comm, node, s->user, io, diag, dlen);
        if (err && rank == 0)
            *mine = err; /* the agreed message: rank 0 says it */
    }
    int wrote = 0;
    if (!err) {
        int e = s->piece(s->user, names, k, diag, dlen);
        wrote = e == FDT_OK;
        struct stat st;
        for (int i = 0; wrote && i < k; i++)
            if (stat(names[i], &st) == 0)
                io[0] += (uint64_t)st.st_size;
        if (!e && rank == a->fail_rank) {
            e = FDT_EIO;
            snprintf(diag, dlen, "%s: injected failure after the piece was written", names[0]);
        }
        *mine = e;
    }
    /* 2: a write failed, 1: out of memory, 0: all is well (MPI_MAX) */
    int bad = *mine == FDT_OK ? 0 : *mine == FDT_ENOMEM ? 1 : 2, worst = 0;
    if (err)
        bad = err == FDT_ENOMEM ? 1 : 2;
    MPI_Allreduce(&bad, &worst, 1, MPI_INT, MPI_MAX, comm);
    uint64_t cnt[2] = {s->ntets, s->nhull}, *all = NULL;
    if (rank == 0 && !(all = malloc(2 * (size_t)size * sizeof *all)))
        worst = worst ? worst : 1;
    MPI_Gather(cnt, 2, MPI_UINT64_T, all, 2, MPI_UINT64_T, 0, comm);
    if (rank == 0 && !worst) {
        /* the index, last: every piece is there */
        fdt_wr_side *side;
        FILE *f = fdt_wr_side_open(a->path, &side, diag, dlen);
        if (!f) {
            worst = 2;
        } else {
            if (kind == FDT_MPO_VTU)
                put_pvtu(f, a->path, size, s->periodic);
            else
                put_text_index(f, a, kind, s, size, all);
            if (fdt_wr_side_commit(side, diag, dlen) != FDT_IO_OK)
                worst = 2;
        }
        if (worst)
            *mine = FDT_EIO;
    }
    free(all);
    MPI_Bcast(&worst, 1, MPI_INT, 0, comm);
    if (worst) {
        /* all or nothing: this rank's pieces, and (rank 0, which renamed
         * it) the .node */
        for (int i = 0; wrote && i < k; i++)
            (void)remove(names[i]);
        if (rank == 0 && node[0] && !err)
            (void)remove(node);
    }
    /* complete (the index is there) or removed, on every rank: nothing to
     * undo */
    MPI_Barrier(comm);
    unguard_all(slot, nl);
    return worst == 0 ? FDT_OK : worst == 1 ? FDT_ENOMEM : FDT_EIO;
}
