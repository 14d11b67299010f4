/*
 * frontdt: exact 3D Delaunay tetrahedralization by Tanemura's advancing
 * front, parallelised after M. L. Merriam (NASA TM-103951, 1992).
 *
 * This is the whole public API. Every name starts with fdt_ / FDT_.
 * Functions return 0 (FDT_OK) or a negative FDT_E* code; the library never
 * exits, never longjmps and never prints.
 *
 * Ownership: pointers passed in are borrowed for the duration of the call
 * unless a comment says otherwise; pointers returned by fdt_result_* getters
 * are owned by the result and live until fdt_result_free().
 *
 * ABI: the structs that may grow (fdt_settings, fdt_stats,
 * fdt_thread_stats) start with `size_t struct_size`, the sizeof the caller
 * compiled against. The inline wrappers below (fdt_default_settings,
 * fdt_result_stats, fdt_result_thread_stats) pass that sizeof to the
 * exported *_sized functions, so a program built against this header keeps
 * working with a later library whose structs are longer: the library reads
 * and writes only the caller's bytes. Rules:
 *   - fields are only ever added at the end, never removed or reordered;
 *   - the library accepts the sizes of this and of every earlier release
 *     of a struct; any other size (0, too small, larger than the library
 *     knows) is refused with FDT_EINVAL and nothing is written;
 *   - an fdt_settings must come from fdt_default_settings() (which sets
 *     struct_size); one zeroed by hand is refused by fdt_open().
 * Today every struct has one size (the first release's), except
 * fdt_stats, which has three: the first release's (ending at t_mesh),
 * 0.1's with the memory fields (mem_points ..), and this one's with the
 * one-part engine's (final_tets ..); and fdt_read_options, which has two
 * (0.1's ended before delimiter).
 * fdt_read_options and fdt_write_options (file formats, at the end) follow
 * the same rule.
 */
#ifndef FRONTDT_H
#define FRONTDT_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(FDT_BUILDING_LIBRARY) && defined(__GNUC__)
#define FDT_API __attribute__((visibility("default")))
#else
#define FDT_API
#endif

#define FDT_VERSION_MAJOR 0
#define FDT_VERSION_MINOR 1
#define FDT_VERSION_PATCH 0
#define FDT_VERSION_STRING "0.1.0"

/* A vertex id: an index into the caller's point array. */
typedef int32_t fdt_vid;
#define FDT_VID_MAX INT32_MAX
/* A tetrahedron id: an index into fdt_result_tets() (in units of tets). */
typedef int64_t fdt_tid;
#define FDT_TID_MAX INT64_MAX

enum {
    FDT_OK = 0,
    FDT_EINVAL = -1,      /* invalid argument or setting */
    FDT_ENOMEM = -2,      /* out of memory */
    FDT_EDEGENERATE = -3, /* fewer than 4 distinct points, or all coplanar */
    FDT_ERANGE = -4,      /* a coordinate is NaN or infinite; for the Voronoi
                             cells and natural-neighbour interpolation, points
                             beyond what doubles hold (the diagnostic says) */
    FDT_ETOOBIG = -5,     /* more points or tets than the index types hold */
    FDT_ECHECK = -6,      /* fdt_check found the mesh is not the Delaunay mesh */
    FDT_ECANCELED = -7,   /* the progress callback asked to stop */
    FDT_EINTERNAL = -8,   /* an internal invariant failed (a bug: please report) */
    FDT_ETHREAD = -9,     /* a thread could not be created */
    FDT_EIO = -10,        /* a file could not be opened, read, written or
                             renamed (fdt_read_points, fdt_write_mesh) */
    FDT_EFORMAT = -11     /* a malformed input file: bad line or byte,
                             NaN/Inf, counts that do not match, no points */
};

/* A static English description of an FDT_E* code (never NULL). */
FDT_API const char *fdt_strerror(int err);
FDT_API const char *fdt_version(void);

typedef enum fdt_mode {
    FDT_MODE_AUTO = 0,    /* serial for one thread, shared otherwise; where
                             the kd search degenerates (scans, grids,
                             cospherical sets) the threads first build the
                             Delaunay mesh of every point together and
                             every part's front reads its apexes from it */
    FDT_MODE_SERIAL = 1,  /* one thread, no mailbox: the reference */
    FDT_MODE_SHARED = 2,  /* threads read each other's points (Cray-2 style) */
    FDT_MODE_MESSAGE = 3  /* remote range queries travel as NODESEND/NODERECV */
} fdt_mode;

/*
 * How a front face's apex is found. Every choice gives the same mesh (the
 * perturbed Delaunay tetrahedralization is unique); they differ in cost.
 */
typedef enum fdt_search {
    FDT_SEARCH_AUTO = 0,  /* in memory, serial or with FDT_MODE_AUTO: the
                             one-part engine, the certified insertion mesh
                             of every point (built on the run's threads) is
                             the answer (no front); streamed, or with an
                             explicit parallel mode: the kd search (§2.2,
                             §4), switching to an insertion mesh where
                             searches get expensive (scans, CFD grids,
                             cospherical sets): serial, the mesh of the
                             points; with threads, one mesh of every point
                             that all parts read. Every mesh is certified
                             first (FDT_ECHECK when it fails) */
    FDT_SEARCH_KD = 1,    /* the kd search only */
    FDT_SEARCH_MESH = 2   /* each part's insertion mesh from the start */
} fdt_search;

/* The name users type for search s (the CLI's --search NAME, the Python
 * module's search='NAME': "auto", "kd", "mesh"), static; NULL when s is
 * not an fdt_search. The searches are the values from 0 up to the first
 * NULL. */
FDT_API const char *fdt_search_name(fdt_search s);
/* Sets *out to the search named name (exactly, as fdt_search_name spells
 * it): FDT_OK, or FDT_EINVAL for an unknown name or a NULL argument (*out
 * unchanged). */
FDT_API int fdt_search_from_name(const char *name, fdt_search *out);

/*
 * The engine a run took (fdt_stats.engine): a function of the settings,
 * the thread count and, for the parts' fronts with FDT_SEARCH_AUTO, a
 * probe that counts the points a search tests on samples of the input;
 * never of a clock, so the same input and settings take the same engine
 * on every run (doc/design.md, "The apex oracle").
 */
typedef enum fdt_engine {
    FDT_ENGINE_FRONT = 1,     /* one front, the paper's method (serial) */
    FDT_ENGINE_ONE_PART,      /* the certified insertion mesh of every
                                 point is the answer, no front */
    FDT_ENGINE_SWEEP,         /* parts in sweep order: each slab's mesh,
                                 its final tets out, the rest carried (a
                                 streamed run) */
    FDT_ENGINE_PARTS,         /* parts with fronts and messages, the kd
                                 search (§3-§5) */
    FDT_ENGINE_PARTS_MESH,    /* the same parts reading their apexes from
                                 the mesh of every point */
    FDT_ENGINE_WALLS,         /* each part's own mesh, its final tets at
                                 once, fronts and messages at the walls */
    FDT_ENGINE_PERIODIC       /* a periodic run (settings.periodic): the
                                 insertion mesh of the points and their
                                 images near the box, the tets of one
                                 copy kept, proved sound and complete */
} fdt_engine;

/* The engine's short name ("front", "one-part", "sweep", "parts",
 * "parts-mesh", "walls", "periodic"; --stats-json's "engine") and a line saying what
 * it does (--stats), static; NULL when e is not an fdt_engine. */
FDT_API const char *fdt_engine_name(int e);
FDT_API const char *fdt_engine_about(int e);

/*
 * Progress callback: called now and then from the calling thread with the
 * fraction of tetrahedra believed built (an estimate in [0, 1]). Return
 * nonzero to cancel: fdt_triangulate() then returns FDT_ECANCELED.
 */
typedef int (*fdt_progress_fn)(void *user, double fraction);

typedef struct fdt_settings {
    size_t struct_size;      /* sizeof(fdt_settings) as compiled by the caller:
                                set by fdt_default_settings (ABI, above) */
    fdt_mode mode;
    int n_threads;           /* 0: one per physical core (hwloc) */
    int pin;                 /* nonzero: bind thread i to core i (the
                                parts' threads: a threaded run with it
                                runs the parts, never the one-part
                                engine) */
    int leaf_size;           /* kd-tree points per leaf, default 30 (the paper's 18, §4, tuned again) */
    int neighbors;           /* nonzero: compute tet neighbours */
    fdt_progress_fn progress;/* may be NULL */
    void *progress_user;     /* borrowed, passed back to progress */
    fdt_search search;       /* default FDT_SEARCH_AUTO */
    int permute_input;       /* nonzero: fdt_triangulate and
                                fdt_triangulate_stream may keep their
                                copy of the points in the caller's xyz
                                array (which must then be writable: the
                                const is cast away), saving 24 bytes a
                                point; on return, success or not, xyz
                                holds the distinct points scaled by a
                                power of two in an unspecified order.
                                Default 0: xyz is only read. (Added after
                                the first release in what was padding:
                                sizeof(fdt_settings) did not change.) */
    /* Periodic domains (issue 33; added after the first release, whose
     * smaller struct_size is still accepted). periodic: bit 0, 1, 2 set
     * when x, y, z is periodic (0, the default: none); periodic_box:
     * xmin, ymin, zmin, xmax, ymax, zmax, read on the periodic axes only,
     * where the period is max - min (the real difference) and every
     * point must lie in [min, max). The result is the Delaunay
     * tetrahedralization of the periodic point set, every tet once, each
     * vertex an input point with an image offset
     * (fdt_result_tet_offsets). In memory (fdt_triangulate), or streamed
     * (fdt_triangulate_stream with fdt_sink's periodic_tets: the box in
     * slabs along its longest periodic axis, a slab's mesh at a time,
     * the same rows), never with neighbours. */
    unsigned periodic;
    double periodic_box[6];
} fdt_settings;

/*
 * Fills the first struct_size bytes of *s with the defaults and sets
 * s->struct_size. FDT_EINVAL for a size this library does not know (ABI,
 * above): then only s->struct_size is written, as 0, when the size leaves
 * room for it, so that fdt_open() refuses the settings.
 */
FDT_API int fdt_default_settings_sized(fdt_settings *s, size_t struct_size);
/* The defaults for the fdt_settings of this header. */
static inline void fdt_default_settings(fdt_settings *s)
{
    (void)fdt_default_settings_sized(s, sizeof *s);
}

typedef struct fdt_context fdt_context;
typedef struct fdt_result fdt_result;

/* Creates a context from settings (copied). *ctx is NULL on failure;
 * FDT_EINVAL for an invalid setting or a struct_size this library does not
 * know (ABI, above). */
FDT_API int fdt_open(fdt_context **ctx, const fdt_settings *s);
/* Frees the context and sets *ctx to NULL; NULL is fine. */
FDT_API void fdt_close(fdt_context **ctx);

/* Whether a run with settings s takes the insertion engine (fdt_search's
 * FDT_SEARCH_AUTO) rather than fronts: in memory (streamed 0,
 * fdt_triangulate) the one-part engine, whose insertion mesh of every
 * point, built on the run's threads, is the answer; streamed (nonzero,
 * fdt_triangulate_stream) the parts in sweep order, the same meshes a slab
 * at a time. A function of the settings alone; for a caller's memory
 * estimate. 0 for a search that is not an fdt_search (fdt_open refuses
 * it). */
FDT_API int fdt_engine_one_part(const fdt_settings *s, int streamed);

/*
 * Triangulates n points. xyz holds 3n doubles (x0 y0 z0 x1 ...), borrowed:
 * it is read during the call only. Duplicate points (bit-identical
 * coordinates, with -0 equal to +0) are merged into their first index.
 * On success *out is a new result owned by the caller (fdt_result_free).
 * On FDT_EDEGENERATE / FDT_ERANGE, fdt_context_diagnostic() says why and
 * which point.
 */
FDT_API int fdt_triangulate(fdt_context *ctx, const double *xyz, size_t n,
                            fdt_result **out);
/* The diagnostic of the last failed call on ctx ("" if none). Owned by ctx. */
FDT_API const char *fdt_context_diagnostic(const fdt_context *ctx);

FDT_API void fdt_result_free(fdt_result **r);

/* Number of tetrahedra; tets() holds 4 vertex ids per tet, in the caller's
 * input numbering, positively oriented: (b-a, c-a, d-a) has a positive
 * determinant. */
FDT_API size_t fdt_result_num_tets(const fdt_result *r);
FDT_API const fdt_vid *fdt_result_tets(const fdt_result *r);
/* 4 per tet: neighbour across the face opposite vertex i, -1 on the hull.
 * NULL unless settings.neighbors was set. */
FDT_API const fdt_tid *fdt_result_neighbors(const fdt_result *r);
/* Hull faces: 3 vertex ids each, ordered so the hull's interior is on the
 * negative side (outward normals by the right-hand rule). */
FDT_API size_t fdt_result_num_hull_faces(const fdt_result *r);
FDT_API const fdt_vid *fdt_result_hull_faces(const fdt_result *r);
/*
 * A periodic run's image offsets (settings.periodic), NULL for any other
 * run: 12 per tet (x, y, z in periods for each of its 4 vertices) and 9
 * per hull face. A periodic result's tets are not oriented: each is its
 * 4 input ids ascending (ties by offsets) with offsets relative to the
 * first, the tets in ascending order (the .tets file's lines), and
 * likewise the hull faces (only across the axes that are not periodic).
 * The face list, edges, adjacency, neighbours and check refuse a
 * periodic result (FDT_EINVAL); fdt_locate and fdt_interpolate (both
 * methods) find queries in it; fdt_result_hash is the hash of its .tets text,
 * fdt_result_set_hash that of its rows with their offsets;
 * fdt_voronoi_compute gives its periodic cells.
 */
FDT_API const int8_t *fdt_result_tet_offsets(const fdt_result *r);
FDT_API const int8_t *fdt_result_hull_offsets(const fdt_result *r);
/* A periodic run's axes (settings.periodic; 0 for any other run) and, when
 * box is not NULL and the run is periodic, its box (settings.periodic_box). */
FDT_API unsigned fdt_result_periodic(const fdt_result *r, double box[6]);

/* n entries: the vertex each input point was merged into (itself when it
 * is the first of its coordinates). */
FDT_API const fdt_vid *fdt_result_duplicate_map(const fdt_result *r);
FDT_API size_t fdt_result_num_duplicates(const fdt_result *r);

/*
 * The face list of Merriam §2: every face once, with its three vertices
 * and the tets on either side (the paper's connectivity of the finished
 * triangulation).
 *
 * Every face once (3 vertex ids, input numbering, oriented so tets[2i] is on
 * its positive side: orient3d(v0,v1,v2,x) > 0 for x the tet's 4th vertex),
 * and the tets on either side (tets[2i+1] = -1 on the hull). Computed on
 * first call (O(n log n) or O(n) expected); arrays owned by the result,
 * valid until fdt_result_free or fdt_result_sort.
 *
 * Precisely: orient3d(a,b,c,d) is the sign of det[b-a; c-a; d-a], positive
 * when d lies on the side of the plane abc towards which the right-hand
 * normal (b-a) x (c-a) points (the sign convention of the tets, above). So
 * face i's right-hand normal points into tet tets[2i] and, for an interior
 * face, out of tets[2i+1]. Further:
 *  - interior faces have tets[2i] < tets[2i+1];
 *  - v0 is the lowest of the three ids (a rotation, which keeps the
 *    orientation);
 *  - faces are in ascending order of their three ids sorted ascending, so
 *    the list is the same for every thread count and mode once the tets
 *    are sorted (fdt_result_sort);
 *  - a hull face (tets[2i+1] = -1) is a face of fdt_result_hull_faces
 *    with the opposite orientation (those have the interior on the
 *    negative side); n_faces = (4 T + H) / 2 for T tets and H hull faces.
 * Returns FDT_ENOMEM (the result unchanged: call again), FDT_EINVAL for a
 * NULL argument.
 */
FDT_API int fdt_result_faces(fdt_result *r, size_t *n_faces, const fdt_vid **verts,
                             const fdt_tid **tets);
/* Every edge once, as (a, b) with a < b, sorted. Owned by the result (valid
 * until fdt_result_free; fdt_result_sort does not change it). */
FDT_API int fdt_result_edges(fdt_result *r, size_t *n_edges, const fdt_vid **verts);
/* The Delaunay neighbours of vertex v, ascending; *ids owned by the result (valid until the
 * next call on r). FDT_EINVAL for a bad v (negative, or not below the number of input
 * points). A duplicate point merged into another (fdt_result_duplicate_map) has no
 * neighbours: *count = 0. */
FDT_API int fdt_result_vertex_neighbors(fdt_result *r, fdt_vid v, size_t *count,
                                        const fdt_vid **ids);

/* Puts the tets in canonical order: by their 4 ids sorted ascending,
 * compared as integer tuples. Each tet keeps its positive orientation;
 * neighbours are renumbered to match. Idempotent. The arrays may move:
 * take fdt_result_tets() and fdt_result_neighbors() again afterwards (and
 * after fdt_result_hash, which sorts). */
FDT_API int fdt_result_sort(fdt_result *r);

/* A checksum of the tet set, independent of tet order, vertex order within
 * a tet, thread count and mode: FNV-1a 64 (offset basis 14695981039346656037,
 * prime 1099511628211) over the bytes of the canonical text: each tet's ids
 * ascending in decimal, "a b c d\n", lines in ascending order (the exact
 * content of a .tets file). Sorts r first (fdt_result_sort). */
FDT_API int fdt_result_hash(fdt_result *r, uint64_t *hash);

/* The set hash of r's tets (src/base/sethash.h): an order-independent 64-bit
 * hash of the tet set, the same for every mode, thread count and order of
 * emission, with no sort (r is not changed). It differs from
 * fdt_result_hash's value. A streamed result (fdt_triangulate_stream),
 * which holds no tets, gives the set hash of the tets it emitted. A
 * periodic run's rows hash with their offsets (src/base/sethash.h), in
 * memory and streamed alike. */
FDT_API int fdt_result_set_hash(const fdt_result *r, uint64_t *hash);

/*
 * Streaming (issue 18): the tets leave as the front builds them (they are
 * final when built, DESIGN.md, Output) instead of being kept in the result.
 *
 * tets: called with batches of finished tets, 4 ids each, in the caller's
 *   numbering (as fdt_result_tets), positively oriented; every tet of the
 *   mesh exactly once, in no particular order. The library serializes the
 *   calls (never two at once) but may make them from any of its threads:
 *   each of its threads fills a batch of its own (up to 65,536 tets) and
 *   hands it over under one lock, so what a call wrote is seen by the next.
 *   A nonzero return stops the run: fdt_triangulate_stream then returns
 *   FDT_ECANCELED (or the value, if it is a negative FDT_E* code).
 * hull: as tets for the hull faces, 3 ids each, outward (may be NULL).
 * The pointers passed are valid during the call only.
 */
typedef struct fdt_sink {
    size_t struct_size; /* sizeof(fdt_sink) as compiled by the caller */
    int (*tets)(void *user, const fdt_vid *tets, size_t count);
    int (*hull)(void *user, const fdt_vid *faces, size_t count);
    void *user;
    /* A periodic run's rows (settings.periodic, issue 33; added after
     * user: a caller compiled before passes the smaller size, still
     * accepted, and cannot stream a periodic run). Called instead of tets
     * and hull: each batch rows as fdt_result_tets and
     * fdt_result_tet_offsets give them (4 input ids ascending, 12
     * offsets relative to the first; hull faces 3 and 9), the rows of a
     * batch in ascending order, each row of the periodic mesh in exactly
     * one batch; batches come in no particular order. periodic_tets must
     * be set to stream a periodic run, periodic_hull may be NULL. */
    int (*periodic_tets)(void *user, const fdt_vid *tets, const int8_t *offsets, size_t count);
    int (*periodic_hull)(void *user, const fdt_vid *faces, const int8_t *offsets, size_t count);
} fdt_sink;

/*
 * As fdt_triangulate, but the tets and hull faces go to sink as they are
 * built. *out is a result with no tets and no hull faces (num_tets 0):
 * its stats (stats.tets counts the tets emitted), its duplicate map and
 * its set hash (fdt_result_set_hash). settings.neighbors is refused
 * (FDT_EINVAL). On failure *out is NULL and some tets may already have
 * gone to the sink. Memory is the points, the search structure and the
 * front, not the mesh (with settings.permute_input about 60 bytes a
 * uniform point; README, Streaming).
 */
FDT_API int fdt_triangulate_stream(fdt_context *ctx, const double *xyz, size_t n,
                                   const fdt_sink *sink, fdt_result **out);

/*
 * The kinds of message between parts (Merriam §4; DESIGN.md, Transport),
 * the index of the message statistics (fdt_stats.sent, .received). 0 is
 * not a kind (its slot stays 0); a new kind takes the next number.
 */
typedef enum fdt_msg_kind {
    FDT_MSG_IAMDONE = 1,  /* "no work left anywhere": ends a run */
    FDT_MSG_NODESEND = 2, /* range queries to another partition */
    FDT_MSG_NODERECV = 3, /* their answers */
    FDT_MSG_FACESEND = 4, /* faces, and found apexes, for their owner */
    FDT_MSG_FACERECV = 5, /* acknowledgements of FACESEND (message mode;
                             shared mode needs none: 0, src/par/termination.c) */
    FDT_MSG_ABORT = 6,    /* a part failed: stop (message mode) */
    FDT_MSG_KIND_END = 7  /* arrays indexed by kind have this many slots */
} fdt_msg_kind;

/* The name of a kind, "IAMDONE", "NODESEND", ...; "?" for anything else.
 * Never NULL; a static string. */
FDT_API const char *fdt_msg_kind_name(int kind);

typedef struct fdt_stats {
    size_t struct_size;       /* bytes the library filled: the caller's
                                 sizeof(fdt_stats) (ABI, above) */
    size_t points;            /* input points */
    size_t vertices;          /* distinct points */
    size_t tets;
    size_t hull_faces;
    size_t faces_advanced;    /* apex searches performed */
    size_t kd_nodes_visited;
    size_t points_tested;     /* points examined by range queries */
    size_t exact_orient;      /* orient3d calls that needed exact arithmetic */
    size_t exact_insphere;    /* insphere calls that needed exact arithmetic */
    size_t adapt_orient;      /* orient3d calls the filters left undecided and
                                 the adaptive stage decided (not in exact_) */
    size_t adapt_insphere;    /* insphere calls likewise */
    size_t max_front;         /* largest front size */
    int threads;
    fdt_mode mode;
    double t_prepare;         /* seconds: validate, merge, scale, kd-tree */
    double t_front;           /* seconds: advancing the front */
    double t_finish;          /* seconds: renumbering, neighbours */
    /* The parallel modes (shared, message); zero in serial mode. */
    size_t sent[FDT_MSG_KIND_END];     /* messages sent by kind, summed over
                                          threads (slot 0 unused) */
    size_t received[FDT_MSG_KIND_END]; /* received by kind (equal to sent:
                                          checked) */
    size_t remote_queries;    /* range queries sent to other partitions */
    size_t remote_answered;   /* range queries answered for other partitions */
    size_t remote_improved;   /* answers that improved the asker's apex */
    size_t tet_requests;      /* apexes found by one partition for a tet
                                 another owns (FACESEND with an apex) */
    size_t duplicate_requests;/* requests for a tet already built */
    double t_idle;            /* seconds threads waited with no work (sum) */
    double t_query_wait;      /* seconds waiting for remote answers (sum) */
    double load_imbalance;    /* max / mean tets built per thread (1: even) */
    int pinned;               /* 1: threads bound to cores; 0: not asked;
                                 -1: asked but refused or unavailable */
    /* The insertion mesh (fdt_search). */
    size_t mesh_faces;        /* faces whose apex the mesh gave */
    size_t mesh_parts;        /* parts that read an insertion mesh: their
                                 own, or the one of every point (one mesh
                                 read by two parts counts two) */
    double t_mesh;            /* seconds building meshes (summed over threads) */
    /* Memory (issue 18): the bytes each structure held at its largest
     * (all threads together). Added after the first release: a caller
     * compiled without them passes the shorter size and gets the rest. */
    size_t mem_points;        /* the points in tree order (24 a vertex:
                                 in the caller's array with
                                 settings.permute_input), their input
                                 indices (4) and, when there are
                                 duplicates, the duplicate map (4 an input
                                 point; without, the identity is made for
                                 the result after the run) */
    size_t mem_merge;         /* the duplicate merge's hash table (freed
                                 before the front starts) */
    size_t mem_tree;          /* the kd-trees: nodes, cells, leaf maps,
                                 float blocks */
    size_t mem_front;         /* face tables (at their largest capacity)
                                 and face queues (at the end) */
    size_t mem_mesh;          /* tets and hull faces kept in memory (0
                                 when streamed), neighbours included */
    size_t mem_sink;          /* the stream's batches (one per thread) */
    /* The one-part engine (issue 31). Added in 0.2: a 0.1 caller passes
     * a shorter size and gets the fields above. */
    size_t final_tets;        /* tets that went to the sink straight from a
                                 part's certified insertion mesh, with no
                                 front (the one-part engine: all of them;
                                 the wall engine: those inside a part) */
    size_t certified_tets;    /* finite tets the mesh certificates checked
                                 before any was trusted */
    double t_certify;         /* seconds certifying meshes */
    /* The one-part engine's insertion (issue 31). Added in 0.3: an older
     * caller passes a shorter size and gets the fields above. With more
     * than one thread the deferred and serial counts depend on how the
     * threads met (try-locks), so they vary from run to run. */
    size_t ins_conflict_tests;/* conflict tests of the insertion */
    size_t ins_deferred;      /* insertions put off (a tet another thread held,
                                 or the slots spent) */
    size_t ins_serial;        /* points left to the build's serial finish */
    /* Parts in sweep order (issue 31, a streamed run's engine). Added in
     * 0.4: an older caller passes a shorter size and gets the fields
     * above. */
    size_t sweep_parts;       /* parts: slabs of the points in sweep order,
                                 each meshed, certified and freed (a
                                 streamed periodic run's too; 0: the run
                                 took another engine) */
    size_t sweep_reinserted;  /* live vertices a part carried into the next
                                 (inserted again) */
    size_t sweep_max_part;    /* the most points in one part's mesh */
    /* Streamed Voronoi cells (issue 32, fdt_voronoi_stream). Added in 0.5:
     * an older caller passes a shorter size and gets the fields above. */
    size_t cell_batches;      /* batches of cells handed on (0: none asked) */
    size_t cell_held_max;     /* the most emitted tets held at once for
                                 points still live (both sweeps') */
    double t_cells;           /* seconds computing them, within the
                                 triangulation's time (summed over the
                                 sweeps, which run at once) */
    int engine;               /* the fdt_engine that ran (fdt_engine_name) */
    /* A periodic run (issue 33; added after the engine: a caller with the
     * size up to it gets the fields above). */
    size_t periodic_images;   /* images triangulated with the points
                                 (streamed: summed over the parts) */
    size_t periodic_rounds;   /* margins tried (streamed: the most a part
                                 tried) */
} fdt_stats;

/* Fills the first struct_size bytes of *st (its struct_size included).
 * FDT_EINVAL for a NULL argument or an unknown size (nothing written). */
FDT_API int fdt_result_stats_sized(const fdt_result *r, fdt_stats *st, size_t struct_size);
static inline int fdt_result_stats(const fdt_result *r, fdt_stats *st)
{
    return fdt_result_stats_sized(r, st, sizeof *st);
}

/* Statistics of one worker thread of a parallel run. */
typedef struct fdt_thread_stats {
    size_t struct_size;       /* bytes the library filled (ABI, above) */
    size_t points;            /* points of its partition */
    size_t tets;              /* tets it built (it owns) */
    size_t hull_faces;
    size_t faces_advanced;    /* apex searches it performed */
    size_t max_front;         /* largest size of its face table */
    size_t remote_queries, remote_answered, remote_improved;
    size_t tet_requests, duplicate_requests;
    size_t sent[FDT_MSG_KIND_END], received[FDT_MSG_KIND_END]; /* by kind */
    double t_idle, t_query_wait;
    double t_cpu;             /* CPU seconds the thread used (0 if unknown) */
    int core;                 /* core it was bound to, -1 if not pinned */
    size_t mesh_queries;      /* faces another part's insertion mesh
                                 answered for it (shared mode) */
    /* The wall engine (issue 31), added after the fields above: a caller
     * compiled without them passes the shorter size and gets the rest. */
    size_t final_tets;        /* tets of its part's own mesh emitted at
                                 once (circumsphere inside its cell) */
    size_t wall_faces;        /* faces between those and the rest: its
                                 first front */
} fdt_thread_stats;

/* Fills *ts for worker thread 0 <= thread < stats.threads. A serial run
 * reports its one thread. FDT_EINVAL if thread is out of range or the size
 * unknown (nothing written). */
FDT_API int fdt_result_thread_stats_sized(const fdt_result *r, int thread,
                                          fdt_thread_stats *ts, size_t struct_size);
static inline int fdt_result_thread_stats(const fdt_result *r, int thread,
                                          fdt_thread_stats *ts)
{
    return fdt_result_thread_stats_sized(r, thread, ts, sizeof *ts);
}

/*
 * Independent exact verification of a mesh on n points (xyz as above, tets
 * in input numbering, duplicates allowed in xyz but tets must use each
 * coordinate's first index): every tet positively oriented, every interior
 * face shared by exactly two tets (and linked both ways if nbrs is not
 * NULL), hull closed and convex, every point used, and the perturbed
 * empty-sphere condition across every interior face. Returns 0 or
 * FDT_ECHECK with a description in msg (NUL-terminated, truncated to len).
 */
FDT_API int fdt_check(const double *xyz, size_t n, const fdt_vid *tets,
                      size_t ntets, const fdt_tid *nbrs, char *msg,
                      size_t len);

/*
 * The same for a periodic mesh (settings.periodic: fdt_result_tets with
 * fdt_result_tet_offsets, the hull faces with fdt_result_hull_offsets, in
 * any vertex order), periodic along the axes of `periodic` (bits 0-2 for x,
 * y, z) with the box xmin, ymin, zmin, xmax, ymax, zmax: every point a
 * vertex, no flat tet, every face in two tets on its two sides or on the
 * hull (normal to no periodic axis, closed, convex), the perturbed
 * empty-sphere condition across every face on the exact images, and the
 * tets covering the domain once (their volumes the box's, or what the hull
 * encloses in one period). 0, FDT_ECHECK with msg, FDT_EINVAL for a bad
 * axis set or box, FDT_ENOMEM.
 */
FDT_API int fdt_check_periodic(const double *xyz, size_t n, const fdt_vid *tets,
                               const int8_t *offsets, size_t ntets, const fdt_vid *hull,
                               const int8_t *hull_offsets, size_t nhull, unsigned periodic,
                               const double box[6], char *msg, size_t len);

/* ------------------------------------------------------------------------ */
/* File formats: reading point clouds, writing meshes                       */
/* ------------------------------------------------------------------------ */

/*
 * The readers and writers of the frontdt CLI, for programs that want the
 * formats without it. Diagnostics (diag, NUL-terminated, cut to diag_size;
 * diag may be NULL when diag_size is 0) are one line naming the file and,
 * for a malformed input, the line (text, counted from 1) or the byte offset
 * (binary PLY), e.g.
 *   "pts.xyz:17: expected 3 numbers, found 2"
 *   "cloud.ply: byte 1032: file ends inside vertex 40 of 1000"
 * They are "" on success. Not for signal handlers; calls on different
 * files may run on different threads (fdt_write_mesh serializes itself).
 */

/* Progress of a read or a write, called now and then on the calling
 * thread: done bytes of total. total is 0 while a pipe is loaded (size not
 * known); for FDT_STAGE_WRITE it is an estimate of the bytes every file of
 * the output will hold, raised to done where that is more. */
typedef void (*fdt_io_progress_fn)(void *user, int stage, uint64_t done, uint64_t total);
enum {
    FDT_STAGE_LOAD = 0,   /* bytes read from the file or pipe */
    FDT_STAGE_PARSE = 1,  /* bytes parsed */
    FDT_STAGE_WRITE = 2   /* bytes written (all files of the output) */
};

typedef struct fdt_read_options {
    size_t struct_size;   /* set by fdt_default_read_options (ABI, above) */
    const char *format;   /* "xyz", "txt", "csv", "node", "ply" (any case),
                             or NULL: by the path's extension (borrowed) */
    int columns[3];       /* x, y, z columns of xyz/txt/csv text, counted
                             from 1 as cut -f counts; {0, 0, 0}: 1, 2, 3.
                             Other columns than 1, 2, 3 with node or ply:
                             FDT_EINVAL */
    int n_threads;        /* threads parsing xyz/txt/csv text (cut at line
                             ends, joined in file order: same points and
                             messages for every count); 0 or 1: the
                             calling thread only */
    fdt_io_progress_fn progress; /* may be NULL; stages LOAD and PARSE */
    void *progress_user;  /* borrowed, passed back to progress */
    /* Added in 0.2 (a 0.1 struct_size, without them, reads as 0 and 0): */
    char delimiter;       /* xyz/txt/csv: the field separator besides
                             blanks, ',' or ';'; ' ' for blanks only; 0:
                             ',', refusing a line that mixes blank and
                             tight-comma separators ("0,5 1,25 2", FDT_EFORMAT) */
    int decimal_comma;    /* xyz/txt/csv: ',' is the decimal mark; the
                             delimiter must then not be ',' (0: blanks) */
} fdt_read_options;

/* Fills the first struct_size bytes of *o with the defaults (format by
 * extension, columns 1 2 3, one thread, no progress). FDT_EINVAL for a
 * size this library does not know (then only struct_size is written, as
 * 0, when it fits, so that the read refuses the options). */
FDT_API int fdt_default_read_options_sized(fdt_read_options *o, size_t struct_size);
static inline void fdt_default_read_options(fdt_read_options *o)
{
    (void)fdt_default_read_options_sized(o, sizeof *o);
}

/*
 * Reads every point of a file: x y z text (.xyz .txt .csv: blanks or one
 * comma between fields, '#' comments, a header line of names skipped,
 * further columns ignored), TetGen .node, or .ply (ascii, binary little or
 * big endian; any scalar type). format: as fdt_read_options.format. path
 * "-" is standard input (read to its end; it has no extension, so format
 * must be given; messages call it "stdin"). The rules of each format are
 * the CLI's (README, "Using the CLI" and "Limits").
 *
 * On success *xyz holds 3 * *n doubles (x0 y0 z0 x1 ...), allocated by the
 * library and owned by the caller, who frees it with fdt_free(). On
 * failure *xyz is NULL, *n is 0 and diag says why:
 *   FDT_EIO      missing or unreadable file, a directory;
 *   FDT_EFORMAT  malformed content (diag names the line or byte), NaN or
 *                Inf, numbers out of double range, no points, more than
 *                FDT_VID_MAX points;
 *   FDT_EINVAL   a NULL argument, an unknown format or extension, "-"
 *                without a format, columns the format does not have, an
 *                options struct_size this library does not know;
 *   FDT_ENOMEM   out of memory (nothing leaked).
 * A header count the file cannot hold is refused before any allocation.
 */
FDT_API int fdt_read_points(const char *path, const char *format, double **xyz, size_t *n,
                            char *diag, size_t diag_size);
/* The same with options (o: borrowed; NULL: the defaults). */
FDT_API int fdt_read_points_opts(const char *path, const fdt_read_options *o, double **xyz,
                                 size_t *n, char *diag, size_t diag_size);

typedef struct fdt_write_options {
    size_t struct_size;   /* set by fdt_default_write_options (ABI, above) */
    const char *format;   /* a format name below, or NULL: by the path's
                             extension (borrowed) */
    int all_faces;        /* TetGen .face: every face (TetGen -f), marker 1
                             on the hull and 0 inside; 0: hull faces only */
    fdt_io_progress_fn progress; /* may be NULL; stage WRITE */
    void *progress_user;  /* borrowed, passed back to progress */
} fdt_write_options;

/* As fdt_default_read_options: no format (by extension), hull faces only,
 * no progress. */
FDT_API int fdt_default_write_options_sized(fdt_write_options *o, size_t struct_size);
static inline void fdt_default_write_options(fdt_write_options *o)
{
    (void)fdt_default_write_options_sized(o, sizeof *o);
}

/*
 * Writes the mesh r of the n points xyz (those given to fdt_triangulate,
 * borrowed) to path, in the format named (NULL: by path's extension):
 *   tets     .tets   canonical text: each tet's 4 ids ascending, one a
 *                    line, lines ascending (the bytes fdt_result_hash hashes)
 *   tetgen   .ele    TetGen BASE.node, BASE.ele, BASE.face, BASE.neigh,
 *                    0-based (needs settings.neighbors)
 *   vtu      .vtu    VTK XML unstructured grid (ParaView), binary appended
 *   vtk      .vtk    VTK legacy ASCII
 *   msh      .msh    gmsh 4.1 ASCII: tets and outward hull triangles
 *   msh2             gmsh 2.2 ASCII (by name only)
 *   medit    .mesh   Medit (MMG, meshio)
 *   openfoam polyMesh  an OpenFOAM polyMesh directory (a path whose last
 *                    component is polyMesh): points, faces, owner,
 *                    neighbour, boundary (the hull one patch)
 * Every file is written to a temporary beside its target and renamed over
 * it only when complete; several files (TetGen, OpenFOAM) are renamed all
 * or none. A failed write leaves neither a temporary nor a partial mesh.
 * path "-" writes a single-file text format (tets, vtk, msh, msh2, medit)
 * to standard output, with no temporary.
 *
 * The target is replaced whatever it is: this function cannot know which
 * file was your input, so never passing your input's path (or, for
 * TetGen, its BASE.node) is the caller's duty (the CLI refuses an output
 * that is its input by any name). A symbolic link at the target is
 * replaced by the new file, not written through.
 *
 * r is not const: the tets format needs canonical order and sorts r in
 * place first (fdt_result_sort, as fdt_result_hash does: take
 * fdt_result_tets and fdt_result_neighbors again afterwards), and openfoam
 * and all_faces compute r's face list (fdt_result_faces). Other formats
 * leave r as it is.
 *
 * Returns FDT_OK, or with diag (naming the file):
 *   FDT_EIO      a file could not be created, written, closed or renamed
 *                (no permission, a missing directory, a full disk);
 *   FDT_EINVAL   a NULL argument, an unknown format or extension, n not the
 *                result's point count, tetgen without neighbours, a binary
 *                or multi-file format to "-", an unknown struct_size;
 *   FDT_ENOMEM   out of memory (nothing left behind).
 * One write runs at a time in a process (an internal lock). A process
 * killed while writing leaves the temporary (".NAME.tmp.XXXXXX" beside the
 * target) behind unless its signal handler calls fdt_write_cleanup.
 */
FDT_API int fdt_write_mesh(fdt_result *r, const double *xyz, size_t n, const char *path,
                           const char *format, char *diag, size_t diag_size);
/* The same with options (o: borrowed; NULL: the defaults). */
FDT_API int fdt_write_mesh_opts(fdt_result *r, const double *xyz, size_t n, const char *path,
                                const fdt_write_options *o, char *diag, size_t diag_size);

/* Async-signal-safe, for a SIGINT/SIGTERM handler that then ends the
 * process (_exit): removes the temporary files of a write in progress and
 * undoes the renames of a multi-file output not yet complete (each old
 * file put back, a new one that replaced none removed), so nothing partial
 * is left. The interrupted write must not go on after. */
FDT_API void fdt_write_cleanup(void);

/*
 * Streaming writers (issue 18): a mesh file written while the tets are
 * still being built (fdt_triangulate_stream), never holding the mesh. The
 * formats that can (the others need the whole mesh: canonical order,
 * neighbours, a face list):
 *   tetgen   .ele    BASE.node, BASE.ele, BASE.face (hull), 0-based; no
 *                    .neigh (a stale BASE.neigh is removed at the commit:
 *                    it would describe another mesh)
 *   vtu      .vtu    as fdt_write_mesh's
 *   bin      .fdtb   frontdt's compact binary mesh (README, "Binary mesh")
 * The tets are in the order they were given, which a streamed run does
 * not fix: compare two files by their tet sets (fdt_result_set_hash).
 * A periodic run's rows (FDT_STREAM_PERIODIC, fdt_sink's periodic_tets)
 * stream to .tets alone: each batch's rows (ascending) go to a spool of
 * 28 bytes a row, an unlinked temporary beside the target, and the
 * canonical text (all rows ascending, the bytes of fdt_write_mesh's .tets
 * of the same mesh) is merged from it at the commit.
 * Every file goes to a temporary beside its target, renamed over it at
 * the commit (all or none); fdt_write_cleanup removes them too.
 */
typedef struct fdt_stream_writer fdt_stream_writer;
enum {
    FDT_STREAM_IDS64 = 1,     /* bin: 64-bit vertex ids (default 32-bit) */
    FDT_STREAM_NO_POINTS = 2, /* bin: leave the points out */
    FDT_STREAM_PERIODIC = 4   /* a periodic run's rows (tets only) */
};
/* Whether the format named (NULL: chosen by path's extension) can stream:
 * 1, 0, or FDT_EINVAL for an unknown format. */
FDT_API int fdt_stream_format_ok(const char *path, const char *format);
/* Opens the temporaries of path in format (NULL: by extension) and writes
 * what precedes the tets (the n points xyz, read during this call only).
 * flags: FDT_STREAM_*, 0 for the defaults. On failure *w is NULL, nothing
 * is left on disk and diag says why: FDT_EINVAL (an unknown format, one
 * that cannot stream, a NULL argument), FDT_EIO, FDT_ENOMEM. */
FDT_API int fdt_stream_writer_open(fdt_stream_writer **w, const char *path, const char *format,
                                   const double *xyz, size_t n, int flags, char *diag,
                                   size_t diag_size);
/* Fills *sink with callbacks writing to w (sink->user is w); pass it to
 * fdt_triangulate_stream. A failed write makes the callback return FDT_EIO
 * (FDT_ENOMEM, FDT_EINVAL for an id outside 0..n-1), which stops the
 * run; fdt_stream_writer_close then reports it. */
FDT_API int fdt_stream_writer_sink(fdt_stream_writer *w, fdt_sink *sink);
/* commit 1: finishes the files (counts patched), closes them and renames
 * them over their targets, all or none; commit 0 (or an earlier error):
 * removes the temporaries, the targets untouched. Frees *w and sets it to
 * NULL. FDT_OK, or the first error with diag. */
FDT_API int fdt_stream_writer_close(fdt_stream_writer **w, int commit, char *diag,
                                    size_t diag_size);
/* Tets and hull faces written so far (NULL arguments are skipped). */
FDT_API void fdt_stream_writer_counts(const fdt_stream_writer *w, uint64_t *tets,
                                      uint64_t *hull);

/*
 * Voronoi cells (issue 32): each point's cell in the Voronoi diagram of
 * the points, clipped by a box, with the quantities voro++ reports (its
 * %v %F %s %n %f and %C), and the DTFE density. Computed from a result's
 * tets (fdt_triangulate), so the cells are the duals of the exact Delaunay
 * mesh: the same for every thread count, mode and input order.
 *
 * Every cell is clipped by the box (default: the points' bounding box; a
 * given box must hold every point): a cell that lies inside it is summed
 * from its tets, one that leaves it (a hull point's cell is unbounded) is
 * cut from the box by its neighbours' bisector planes, as voro++ cuts
 * every cell. The volumes of a box's cells add up to the box's volume.
 * Sums are exact on a grid of 2^-98 of the box's largest side to the
 * quantity's power (src/base/fixsum.h): the same bits for every order of
 * the tets; a cell of volume V keeps a relative precision of about
 * 2^-98 D^3 / V beside its shares' rounding (1e-10 for V = 3e-20 D^3).
 */
typedef struct fdt_voronoi fdt_voronoi;

typedef struct fdt_voronoi_options {
    size_t struct_size; /* sizeof(fdt_voronoi_options) as compiled by the caller */
    int box_given;      /* nonzero: clip by box, not the points' bounding box */
    double box[6];      /* xmin, ymin, zmin, xmax, ymax, zmax */
    int neighbors;      /* nonzero: keep each cell's neighbours and face areas */
    int threads;        /* 0: one per physical core (as fdt_settings.n_threads);
                           the values do not depend on it */
    /* Added after the cells (a caller compiled before passes the smaller
     * struct_size, still accepted: nothing skipped). FDT_CELLS_NO_* bits:
     * quantities not computed, whose accessors then return NULL; the others
     * are the same bits either way (0, the default: every one). */
    unsigned skip;
} fdt_voronoi_options;

#define FDT_CELLS_NO_CENTROIDS 1u /* fdt_voronoi_centroids */
#define FDT_CELLS_NO_DENSITIES 2u /* fdt_voronoi_densities */

FDT_API int fdt_default_voronoi_options_sized(fdt_voronoi_options *o, size_t struct_size);
static inline void fdt_default_voronoi_options(fdt_voronoi_options *o)
{
    (void)fdt_default_voronoi_options_sized(o, sizeof *o);
}

/* Cell flags (fdt_voronoi_flags). */
#define FDT_CELL_CLIPPED 1u /* the box cut the cell (it left the box) */
#define FDT_CELL_HULL 2u    /* a convex-hull point: the unclipped cell is
                               unbounded, and its DTFE density counts only
                               the tets it has */
#define FDT_CELL_MERGED 4u  /* a duplicate merged into another point
                               (fdt_result_duplicate_map): no cell */

/*
 * The cells of the n points xyz (borrowed, the array r was computed from)
 * from r's tets and hull faces (r is not changed). o may be NULL (the
 * defaults). *out is owned by the caller (fdt_voronoi_free). FDT_EINVAL
 * for a NULL argument, a streamed result (no tets kept), n not r's point
 * count, threads outside 0..1024, an empty or inverted box, or a point outside the given box (diag,
 * when not NULL, says which; it is written in every case, "" on success);
 * FDT_ERANGE when two points are closer than 2^-48 of the box (the cells
 * cut from the box could not be; diag names them); FDT_ENOMEM;
 * FDT_EINTERNAL when a cell could not be cut (a bug).
 * A periodic result (settings.periodic): the cells of the periodic point
 * set in its own box (o's box, when given, must be that box: FDT_EINVAL
 * otherwise), wrapped on the periodic axes and cut by the box's sides
 * across the others, where a point outside the box is FDT_EINVAL; their
 * volumes sum to the box's.
 */
FDT_API int fdt_voronoi_compute(const fdt_result *r, const double *xyz, size_t n,
                                const fdt_voronoi_options *o, fdt_voronoi **out,
                                char *diag, size_t diag_size);
FDT_API void fdt_voronoi_free(fdt_voronoi **v);

/* n entries each (3n for the centroids, absolute coordinates), owned by
 * v. A merged duplicate's entries are 0 (density too). Faces are counted
 * without the faces of zero area (fdt_voronoi_zero_faces). The DTFE
 * density is 4 / (the sum of the volumes of the point's tets). The
 * centroids and densities are NULL where options.skip left them out. */
FDT_API size_t fdt_voronoi_num_points(const fdt_voronoi *v);
/* The rows' points: NULL for fdt_voronoi_compute's cells (row i is point
 * i); for a batch of fdt_voronoi_stream, each row's input id, and its
 * coordinates as given (3 each: the caller's array may have been moved by
 * settings.permute_input). */
FDT_API const fdt_vid *fdt_voronoi_ids(const fdt_voronoi *v);
FDT_API const double *fdt_voronoi_points(const fdt_voronoi *v);
FDT_API const double *fdt_voronoi_volumes(const fdt_voronoi *v);
FDT_API const double *fdt_voronoi_areas(const fdt_voronoi *v);
FDT_API const double *fdt_voronoi_centroids(const fdt_voronoi *v);
FDT_API const int32_t *fdt_voronoi_num_faces(const fdt_voronoi *v);
FDT_API const double *fdt_voronoi_densities(const fdt_voronoi *v);
FDT_API const uint8_t *fdt_voronoi_flags(const fdt_voronoi *v);
/* The box the cells were clipped by (xmin, ymin, zmin, xmax, ymax, zmax). */
FDT_API void fdt_voronoi_box(const fdt_voronoi *v, double box[6]);
/* Faces of area at most 2^-40 of their cell's surface (degenerate points:
 * the extra Delaunay edges of cospherical points), left out of every count
 * and list; how many there were over all cells. */
FDT_API size_t fdt_voronoi_zero_faces(const fdt_voronoi *v);
/* Point i's neighbours, ascending (the box's walls first, as voro++ numbers
 * them: -1 x-min, -2 x-max, -3 y-min, -4 y-max, -5 z-min, -6 z-max), and
 * the area of the face shared with each; both owned by v. FDT_EINVAL when
 * options.neighbors was not set or i is out of range. */
FDT_API int fdt_voronoi_neighbors(const fdt_voronoi *v, fdt_vid i, size_t *count,
                                  const fdt_vid **ids, const double **areas);
/* Point i's cell as a polyhedron (needs options.neighbors; xyz: the points
 * of fdt_voronoi_compute): *nverts vertices (3 doubles each) and *nfaces
 * faces, each as its vertex count then its vertex indices, counter-
 * clockwise seen from outside. Cut from the box by the neighbours'
 * bisectors, as the cut cells are (so a summed cell's polyhedron agrees
 * with its volume to rounding); a periodic set's cell from its point's
 * period box (the point at its centre) on the periodic axes, by the
 * neighbours' images, so that its vertices may lie outside the box.
 * Owned by v, valid until the next call on v (not from two threads at
 * once). A merged duplicate has none (0, 0).
 * FDT_ERANGE when the cell has a neighbour closer than 2^-40 of their
 * coordinates: its vertices, absolute coordinates, would round by as much
 * as the cell is wide. */
FDT_API int fdt_voronoi_polyhedron(fdt_voronoi *v, const double *xyz, fdt_vid i, size_t *nverts,
                                   const double **verts, size_t *nfaces,
                                   const int32_t **faces);

/*
 * Streamed cells (issue 32): the triangulation of fdt_triangulate_stream
 * with each point's Voronoi cell handed to cells->cells as soon as the
 * point's last tet is out, so that no more cells are held than a part's
 * points (the run's parts in sweep order: settings.search FDT_SEARCH_AUTO,
 * FDT_MODE_AUTO or serial, no pin; else FDT_EINVAL, ctx's diagnostic
 * says why). A periodic run (settings.periodic) hands on each slab's
 * points' cells after the slab, as fdt_voronoi_compute computes them on
 * its result (o->box, when given, must be settings.periodic_box). Each batch is an fdt_voronoi of some points' cells, as
 * fdt_voronoi_compute computes them (the same bits, whatever the threads,
 * the parts or the input's order): fdt_voronoi_ids gives each row's input
 * id, and the accessors take rows (fdt_voronoi_neighbors too, with
 * o->neighbors; fdt_voronoi_polyhedron is not available). Every input
 * point is in exactly one batch, the merged duplicates in the last
 * (FDT_CELL_MERGED). The calls are serialized as fdt_sink's (never two
 * at once, from any of the library's threads); the batch is valid during
 * the call only; a nonzero return stops the run (FDT_ECANCELED, or the
 * value if it is a negative FDT_E* code). sink (may be NULL: the tets
 * are counted, hashed and dropped) gets the tets and hull faces as with
 * fdt_triangulate_stream. o: as fdt_voronoi_compute's (its threads are
 * the run's). Errors as fdt_triangulate_stream's and fdt_voronoi_compute's;
 * a point outside the box is reported before any work, two points too
 * close for the cells (FDT_ERANGE) when the run is over, the least such
 * edge named, and cells handed on before then are not to be used.
 */
typedef struct fdt_cell_sink {
    size_t struct_size; /* sizeof(fdt_cell_sink) as compiled by the caller */
    int (*cells)(void *user, const fdt_voronoi *batch);
    void *user;
} fdt_cell_sink;

FDT_API int fdt_voronoi_stream(fdt_context *ctx, const double *xyz, size_t n,
                               const fdt_voronoi_options *o, const fdt_sink *sink,
                               const fdt_cell_sink *cells, fdt_result **out);

/*
 * Point location and interpolation in a result's mesh (issue 32). r is the
 * result of fdt_triangulate on the n points xyz (borrowed; not streamed).
 * Where r keeps no neighbours (settings.neighbors 0) they are derived from
 * its face list, which r then keeps (as fdt_result_faces): not to be
 * called on one such r from two threads at once. threads: 0 for one per physical core (as
 * fdt_settings.n_threads), or 1 to 1024; the results do not depend on it.
 * The queries are taken in Morton order (short walks between them).
 *
 * fdt_locate: for each of the nq queries q (3 doubles each), tet[k], the
 * index of a tet holding it (fdt_result_tets; on a face shared by two,
 * either), or -1 outside the hull (or not finite); when bary is not NULL,
 * its 4 barycentric coordinates in the order of that tet's vertices (0
 * outside). The walk decides with exact orient3d. FDT_EINVAL, FDT_ENOMEM.
 * A periodic r: the row (fdt_result_tets, with its offsets) holding the
 * query wrapped into the box along the periodic axes, the coordinates in
 * the order of that row's ids.
 */
FDT_API int fdt_locate(fdt_result *r, const double *xyz, size_t n, const double *q, size_t nq,
                       fdt_tid *tet, double *bary, int threads);

typedef enum fdt_interp {
    FDT_INTERP_LINEAR = 0,  /* barycentric in the tet holding the query */
    FDT_INTERP_NATURAL = 1  /* Sibson's natural-neighbour coordinates */
} fdt_interp;

/*
 * values: nv values a point (values[nv i + c], input numbering; a merged
 * duplicate's are not read: its first occurrence's are). out: nv values a
 * query. Both methods reproduce linear functions; a query outside the hull
 * gets NaN (natural: on the hull too), one at a point that point's values. FDT_EINVAL, FDT_ENOMEM,
 * FDT_EINTERNAL (diag, when not NULL, names the query).
 * A periodic r (settings.periodic): each query wrapped into the box along
 * the periodic axes and answered in the periodic mesh (the natural
 * neighbours of a query near a side among the images across it); NaN
 * beyond the hull across an axis that is not periodic (natural: on it
 * too); FDT_ERANGE (diag names the query) where the images' rounding to
 * doubles leaves the part of the mesh a query's natural neighbours need
 * not Delaunay (points on a grid or circles across the periods).
 */
FDT_API int fdt_interpolate(fdt_result *r, const double *xyz, size_t n, const double *values,
                            size_t nv, const double *q, size_t nq, fdt_interp method,
                            int threads, double *out, char *diag, size_t diag_size);

/* Frees memory the library allocated for the caller (the points of
 * fdt_read_points). NULL is fine. */
FDT_API void fdt_free(void *p);

#ifdef __cplusplus
}
#endif
#endif /* FRONTDT_H */
