/*
 * frontdt._frontdt: the Python binding of the public API (include/frontdt.h
 * only; issue 17 item 3).
 *
 * delaunay() copies the points into a C-contiguous float64 array, releases
 * the GIL for fdt_triangulate and the canonical sort and hash, and returns a
 * Triangulation that owns the fdt_result. Its arrays (simplices, neighbors,
 * convex_hull, duplicates, ...) are read-only numpy views of the result's
 * memory whose base is the Triangulation, so the result lives as long as
 * any of them and is freed with the last one (no copy of the mesh).
 *
 * Why everything is sorted and hashed up front: fdt_result_sort and
 * fdt_result_hash may move the result's arrays (frontdt.h), which would
 * leave earlier views dangling. Done once before the first view exists, the
 * arrays never move again; it also makes `simplices` the canonical order,
 * the same for every thread count and mode.
 *
 * The tets never change after construction, so check() may release the
 * GIL while other threads read the same Triangulation. The face and edge
 * lists (fdt_result_faces, fdt_result_edges) are derived inside the result
 * on first use; those calls write the result, so they run under the
 * object's own lock (with the GIL released: they take a while on big
 * meshes), and once built their arrays stay until the result is freed.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>

#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "frontdt.h"

static PyObject *CheckError; /* frontdt.CheckError, a RuntimeError */

/* ------------------------------------------------------------ errors */

/* Raises the Python exception for an FDT_E* code: bad input (the caller's
 * points or arguments) is a ValueError carrying the library's diagnostic,
 * which names the point; out of memory a MemoryError; the rest (threads,
 * index range, internal errors) RuntimeError. A pending exception (a
 * KeyboardInterrupt that canceled the run) is left as it is. */
static PyObject *raise_fdt(int err, const char *diag)
{
    if (PyErr_Occurred())
        return NULL;
    const char *what = diag && *diag ? diag : fdt_strerror(err);
    switch (err) {
    case FDT_EDEGENERATE:
    case FDT_ERANGE:
    case FDT_EINVAL:
        PyErr_SetString(PyExc_ValueError, what);
        break;
    case FDT_ENOMEM:
        PyErr_SetString(PyExc_MemoryError, what);
        break;
    case FDT_ECHECK:
        PyErr_SetString(CheckError, what);
        break;
    default:
        PyErr_Format(PyExc_RuntimeError, "%s (%s)", what, fdt_strerror(err));
        break;
    }
    return NULL;
}

/* ------------------------------------------------------------ cancel */

static double mono_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Progress callback: the library calls it from the calling thread, which
 * has released the GIL. At most every 0.25 s it takes the GIL back to run
 * Python's pending signal handlers, so Ctrl-C (KeyboardInterrupt) stops a
 * long triangulation: the handler's exception stays set on this thread and
 * a nonzero return makes fdt_triangulate return FDT_ECANCELED. The GIL is
 * taken rarely because another busy Python thread can keep it for up to
 * the switch interval (5 ms) before handing it over. Handlers run only on
 * the main thread; elsewhere PyErr_CheckSignals returns 0. */
typedef struct cancel_state {
    double next;
} cancel_state;

static int progress_cb(void *user, double fraction)
{
    (void)fraction;
    cancel_state *cs = user;
    double t = mono_s();
    if (t < cs->next)
        return 0;
    cs->next = t + 0.25;
    PyGILState_STATE g = PyGILState_Ensure();
    int stop = PyErr_CheckSignals() != 0;
    PyGILState_Release(g);
    return stop;
}

/* ------------------------------------------------------------ arrays */

/* (n, 3) float64, C-contiguous, a copy the caller cannot change under us
 * (the GIL is released while the library reads it). */
static PyArrayObject *points_array(PyObject *obj)
{
    PyArrayObject *a = (PyArrayObject *)PyArray_FROMANY(
        obj, NPY_DOUBLE, 0, 0,
        NPY_ARRAY_C_CONTIGUOUS | NPY_ARRAY_ALIGNED | NPY_ARRAY_ENSURECOPY);
    if (!a)
        return NULL;
    if (PyArray_NDIM(a) != 2 || PyArray_DIM(a, 1) != 3) {
        PyObject *shape = PyObject_GetAttrString((PyObject *)a, "shape");
        if (shape)
            PyErr_Format(PyExc_ValueError,
                         "points must be an (n, 3) array, got shape %R", shape);
        Py_XDECREF(shape);
        Py_DECREF(a);
        return NULL;
    }
    return a;
}

/* A read-only view of `rows` x `cols` items at data whose base is owner:
 * the view keeps owner (and the memory it owns) alive. */
static PyObject *view(PyObject *owner, const void *data, npy_intp rows,
                      npy_intp cols, int type)
{
    npy_intp dims[2] = {rows, cols};
    PyObject *a = PyArray_SimpleNewFromData(cols ? 2 : 1, dims, type,
                                            (void *)data);
    if (!a)
        return NULL;
    PyArray_CLEARFLAGS((PyArrayObject *)a, NPY_ARRAY_WRITEABLE);
    Py_INCREF(owner);
    if (PyArray_SetBaseObject((PyArrayObject *)a, owner) < 0) {
        Py_DECREF(a); /* SetBaseObject stole the reference even so */
        return NULL;
    }
    return a;
}

/* The i such that name(i) is s (name answers 0, 1, ... up to its first
 * NULL), or -1 with a ValueError that lists the choices. */
static int pick(const char *what, const char *s, const char *(*name)(int i))
{
    char choices[128] = "";
    for (int i = 0; name(i); i++) {
        if (strcmp(s, name(i)) == 0)
            return i;
        size_t used = strlen(choices);
        snprintf(choices + used, sizeof choices - used, "%s'%s'", i ? ", " : "", name(i));
    }
    PyErr_Format(PyExc_ValueError, "%s must be one of %s, got '%s'", what, choices, s);
    return -1;
}

/* ------------------------------------------------------------ Triangulation */

typedef struct {
    PyObject_HEAD
    fdt_result *r;          /* owned; sorted, never changed again */
    PyArrayObject *points;  /* owned copy, (n, 3) float64 */
    uint64_t hash;
    PyThread_type_lock lock;/* serialises the calls that derive lists in r */
} TriObject;

static void tri_dealloc(TriObject *self)
{
    fdt_result_free(&self->r);
    if (self->lock)
        PyThread_free_lock(self->lock);
    Py_XDECREF(self->points);
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static PyObject *tri_simplices(TriObject *self, void *closure)
{
    (void)closure;
    return view((PyObject *)self, fdt_result_tets(self->r),
                (npy_intp)fdt_result_num_tets(self->r), 4, NPY_INT32);
}

static PyObject *tri_neighbors(TriObject *self, void *closure)
{
    (void)closure;
    if (!fdt_result_neighbors(self->r)) /* a periodic mesh: none yet */
        Py_RETURN_NONE;
    return view((PyObject *)self, fdt_result_neighbors(self->r),
                (npy_intp)fdt_result_num_tets(self->r), 4, NPY_INT64);
}

static PyObject *tri_hull(TriObject *self, void *closure)
{
    (void)closure;
    return view((PyObject *)self, fdt_result_hull_faces(self->r),
                (npy_intp)fdt_result_num_hull_faces(self->r), 3, NPY_INT32);
}

/* A periodic run's image offsets, int8 (m, 4, 3); None for a plain run. */
static PyObject *tri_offsets(TriObject *self, void *closure)
{
    (void)closure;
    const int8_t *o = fdt_result_tet_offsets(self->r);
    if (!o)
        Py_RETURN_NONE;
    npy_intp dims[3] = {(npy_intp)fdt_result_num_tets(self->r), 4, 3};
    PyObject *a = PyArray_SimpleNewFromData(3, dims, NPY_INT8, (void *)o);
    if (!a)
        return NULL;
    PyArray_CLEARFLAGS((PyArrayObject *)a, NPY_ARRAY_WRITEABLE);
    Py_INCREF(self);
    if (PyArray_SetBaseObject((PyArrayObject *)a, (PyObject *)self) < 0) {
        Py_DECREF(a);
        return NULL;
    }
    return a;
}

static PyObject *tri_duplicates(TriObject *self, void *closure)
{
    (void)closure;
    return view((PyObject *)self, fdt_result_duplicate_map(self->r),
                PyArray_DIM(self->points, 0), 0, NPY_INT32);
}

/* The face list: computed once (fdt_result_faces), then the same arrays. */
static int tri_faces_impl(TriObject *self, size_t *nf, const fdt_vid **fv,
                          const fdt_tid **ft)
{
    int err;
    Py_BEGIN_ALLOW_THREADS
    PyThread_acquire_lock(self->lock, WAIT_LOCK);
    err = fdt_result_faces(self->r, nf, fv, ft);
    PyThread_release_lock(self->lock);
    Py_END_ALLOW_THREADS
    if (err)
        raise_fdt(err, NULL);
    return err;
}

static PyObject *tri_faces(TriObject *self, void *closure)
{
    (void)closure;
    size_t nf;
    const fdt_vid *fv;
    const fdt_tid *ft;
    if (tri_faces_impl(self, &nf, &fv, &ft))
        return NULL;
    return view((PyObject *)self, fv, (npy_intp)nf, 3, NPY_INT32);
}

static PyObject *tri_face_tets(TriObject *self, void *closure)
{
    (void)closure;
    size_t nf;
    const fdt_vid *fv;
    const fdt_tid *ft;
    if (tri_faces_impl(self, &nf, &fv, &ft))
        return NULL;
    return view((PyObject *)self, ft, (npy_intp)nf, 2, NPY_INT64);
}

static PyObject *tri_edges(TriObject *self, void *closure)
{
    (void)closure;
    size_t ne;
    const fdt_vid *ev;
    int err;
    Py_BEGIN_ALLOW_THREADS
    PyThread_acquire_lock(self->lock, WAIT_LOCK);
    err = fdt_result_edges(self->r, &ne, &ev);
    PyThread_release_lock(self->lock);
    Py_END_ALLOW_THREADS
    if (err)
        return raise_fdt(err, NULL);
    return view((PyObject *)self, ev, (npy_intp)ne, 2, NPY_INT32);
}

/* A copy: the library's array is valid only until its next call on r. */
static PyObject *tri_vertex_neighbors(TriObject *self, PyObject *arg)
{
    long v = PyLong_AsLong(arg);
    if (v == -1 && PyErr_Occurred())
        return NULL;
    if (v < 0 || v >= (long)PyArray_DIM(self->points, 0))
        return PyErr_Format(PyExc_IndexError, "vertex %ld out of range [0, %zd)", v,
                            (Py_ssize_t)PyArray_DIM(self->points, 0));
    size_t cnt = 0;
    const fdt_vid *ids = NULL;
    fdt_vid *copy = NULL;
    int err;
    /* copied under the lock: another thread's call would replace ids */
    Py_BEGIN_ALLOW_THREADS
    PyThread_acquire_lock(self->lock, WAIT_LOCK);
    err = fdt_result_vertex_neighbors(self->r, (fdt_vid)v, &cnt, &ids);
    if (!err && !(copy = malloc((cnt ? cnt : 1) * sizeof *copy)))
        err = FDT_ENOMEM;
    if (!err)
        memcpy(copy, ids, cnt * sizeof *copy);
    PyThread_release_lock(self->lock);
    Py_END_ALLOW_THREADS
    if (err)
        return raise_fdt(err, NULL);
    npy_intp dim = (npy_intp)cnt;
    PyObject *out = PyArray_SimpleNew(1, &dim, NPY_INT32);
    if (out)
        memcpy(PyArray_DATA((PyArrayObject *)out), copy, cnt * sizeof *copy);
    free(copy);
    return out;
}

static PyObject *tri_points(TriObject *self, void *closure)
{
    (void)closure;
    return view((PyObject *)self->points, PyArray_DATA(self->points),
                PyArray_DIM(self->points, 0), 3, NPY_DOUBLE);
}

static PyObject *tri_hash(TriObject *self, void *closure)
{
    (void)closure;
    char s[17];
    snprintf(s, sizeof s, "%016" PRIx64, self->hash);
    return PyUnicode_FromString(s);
}

static const char *mode_name(fdt_mode m)
{
    switch (m) {
    case FDT_MODE_SERIAL: return "serial";
    case FDT_MODE_SHARED: return "shared";
    case FDT_MODE_MESSAGE: return "message";
    default: return "auto";
    }
}

/* Messages by kind, keyed by fdt_msg_kind_name ("iamdone", ...); slot 0
 * is no kind. */
static PyObject *msg_dict(const size_t *m)
{
    PyObject *d = PyDict_New();
    if (!d)
        return NULL;
    for (int k = 1; k < FDT_MSG_KIND_END; k++) {
        char key[32];
        const char *name = fdt_msg_kind_name(k);
        size_t i = 0;
        for (; name[i] && i + 1 < sizeof key; i++)
            key[i] = (char)((name[i] >= 'A' && name[i] <= 'Z') ? name[i] - 'A' + 'a' : name[i]);
        key[i] = '\0';
        PyObject *v = PyLong_FromSize_t(m[k]);
        if (!v || PyDict_SetItemString(d, key, v) != 0) {
            Py_XDECREF(v);
            Py_DECREF(d);
            return NULL;
        }
        Py_DECREF(v);
    }
    return d;
}

/* Sets d[key] = v and drops v; 0 or -1 (v NULL counts as the error). */
static int put(PyObject *d, const char *key, PyObject *v)
{
    if (!v)
        return -1;
    int rc = PyDict_SetItemString(d, key, v);
    Py_DECREF(v);
    return rc;
}

#define PUT_SIZE(d, st, f) put(d, #f, PyLong_FromSize_t((st).f))
#define PUT_DBL(d, st, f) put(d, #f, PyFloat_FromDouble((st).f))

/* fdt_result_stats as a new dict, field names as in fdt_stats. */
static PyObject *tri_stats(TriObject *self, void *closure)
{
    (void)closure;
    fdt_stats st;
    int err = fdt_result_stats(self->r, &st);
    if (err)
        return raise_fdt(err, NULL);
    PyObject *d = PyDict_New();
    if (!d)
        return NULL;
    if (PUT_SIZE(d, st, points) || PUT_SIZE(d, st, vertices) || PUT_SIZE(d, st, tets) ||
        PUT_SIZE(d, st, hull_faces) || PUT_SIZE(d, st, faces_advanced) ||
        PUT_SIZE(d, st, kd_nodes_visited) || PUT_SIZE(d, st, points_tested) ||
        PUT_SIZE(d, st, exact_orient) || PUT_SIZE(d, st, exact_insphere) ||
        PUT_SIZE(d, st, adapt_orient) || PUT_SIZE(d, st, adapt_insphere) ||
        PUT_SIZE(d, st, max_front) || put(d, "threads", PyLong_FromLong(st.threads)) ||
        put(d, "mode", PyUnicode_FromString(mode_name(st.mode))) ||
        put(d, "engine", PyUnicode_FromString(fdt_engine_name(st.engine) ? fdt_engine_name(st.engine)
                                                                          : "unknown")) ||
        PUT_DBL(d, st, t_prepare) || PUT_DBL(d, st, t_front) || PUT_DBL(d, st, t_finish) ||
        put(d, "sent", msg_dict(st.sent)) || put(d, "received", msg_dict(st.received)) ||
        PUT_SIZE(d, st, remote_queries) || PUT_SIZE(d, st, remote_answered) ||
        PUT_SIZE(d, st, remote_improved) || PUT_SIZE(d, st, tet_requests) ||
        PUT_SIZE(d, st, duplicate_requests) || PUT_DBL(d, st, t_idle) ||
        PUT_DBL(d, st, t_query_wait) || PUT_DBL(d, st, load_imbalance) ||
        put(d, "pinned", PyLong_FromLong(st.pinned)) || PUT_SIZE(d, st, mesh_faces) ||
        PUT_SIZE(d, st, mesh_parts) || PUT_DBL(d, st, t_mesh) ||
        PUT_SIZE(d, st, final_tets) || PUT_SIZE(d, st, certified_tets) ||
        PUT_DBL(d, st, t_certify) || PUT_SIZE(d, st, ins_conflict_tests) ||
        PUT_SIZE(d, st, ins_deferred) || PUT_SIZE(d, st, ins_serial) ||
        PUT_SIZE(d, st, sweep_parts) || PUT_SIZE(d, st, sweep_reinserted) ||
        PUT_SIZE(d, st, periodic_images) || PUT_SIZE(d, st, periodic_rounds) ||
        PUT_SIZE(d, st, sweep_max_part) || PUT_SIZE(d, st, cell_batches) ||
        PUT_SIZE(d, st, cell_held_max) || PUT_DBL(d, st, t_cells) ||
        put(d, "duplicates", PyLong_FromSize_t(fdt_result_num_duplicates(self->r)))) {
        Py_DECREF(d);
        return NULL;
    }
    return d;
}

/* Runs fdt_check on n points and a mesh with the GIL released; None or an
 * exception (CheckError with the checker's description). The arrays must
 * stay alive and unchanged during the call: the caller holds them. */
static PyObject *run_check(const double *xyz, size_t n, const fdt_vid *tets,
                           size_t ntets, const fdt_tid *nbrs)
{
    char msg[1024];
    int err;
    Py_BEGIN_ALLOW_THREADS
    err = fdt_check(xyz, n, tets, ntets, nbrs, msg, sizeof msg);
    Py_END_ALLOW_THREADS
    if (err)
        return raise_fdt(err, msg);
    Py_RETURN_NONE;
}

static PyObject *tri_check(TriObject *self, PyObject *unused)
{
    (void)unused;
    double box[6];
    unsigned axes = fdt_result_periodic(self->r, box);
    if (axes) { /* the periodic mesh's own check */
        char msg[1024];
        int err;
        const fdt_result *r = self->r;
        size_t n = (size_t)PyArray_DIM(self->points, 0);
        const double *xyz = PyArray_DATA(self->points);
        Py_BEGIN_ALLOW_THREADS
        err = fdt_check_periodic(xyz, n, fdt_result_tets(r), fdt_result_tet_offsets(r),
                                 fdt_result_num_tets(r), fdt_result_hull_faces(r),
                                 fdt_result_hull_offsets(r), fdt_result_num_hull_faces(r), axes,
                                 box, msg, sizeof msg);
        Py_END_ALLOW_THREADS
        if (err)
            return raise_fdt(err, msg);
        Py_RETURN_NONE;
    }
    return run_check(PyArray_DATA(self->points), (size_t)PyArray_DIM(self->points, 0),
                     fdt_result_tets(self->r), fdt_result_num_tets(self->r),
                     fdt_result_neighbors(self->r));
}

static PyObject *tri_repr(TriObject *self)
{
    return PyUnicode_FromFormat("<frontdt.Triangulation: %zd points, %zu tetrahedra>",
                                (Py_ssize_t)PyArray_DIM(self->points, 0),
                                fdt_result_num_tets(self->r));
}

static PyGetSetDef tri_getset[] = {
    {"points", (getter)tri_points, NULL,
     "The input points, (n, 3) float64 (a copy taken by delaunay()).", NULL},
    {"simplices", (getter)tri_simplices, NULL,
     "Tetrahedra, int32 (m, 4): input point indices, positively oriented "
     "(det(b-a, c-a, d-a) > 0), in canonical order (rows sorted by their "
     "sorted ids; the same for every thread count and mode).", NULL},
    {"neighbors", (getter)tri_neighbors, NULL,
     "int64 (m, 4): row i, column k is the tetrahedron across the face "
     "opposite simplices[i, k], -1 on the convex hull (as in scipy).", NULL},
    {"convex_hull", (getter)tri_hull, NULL,
     "Hull faces, int32 (h, 3), outward normals by the right-hand rule.", NULL},
    {"offsets", (getter)tri_offsets, NULL,
     "A periodic run's image offsets, int8 (m, 4, 3): vertex k of tet i is point "
     "simplices[i, k] moved by offsets[i, k] periods (relative to the tet's first, "
     "lowest-id vertex, whose offsets are 0); None for a plain run. A periodic tet's "
     "ids are ascending, not oriented.", NULL},
    {"duplicates", (getter)tri_duplicates, NULL,
     "int32 (n,): the index each point was merged into (bit-identical "
     "coordinates; itself for the first of its coordinates).", NULL},
    {"faces", (getter)tri_faces, NULL,
     "Every face once, int32 (f, 3) (fdt_result_faces, Merriam §2): "
     "oriented so face_tets[i, 0] is on its positive side (its right-hand "
     "normal points into that tet), lowest id first, rows ascending.", NULL},
    {"face_tets", (getter)tri_face_tets, NULL,
     "int64 (f, 2): the tets on either side of faces[i] (rows of "
     "simplices); face_tets[i, 1] = -1 on the hull.", NULL},
    {"edges", (getter)tri_edges, NULL,
     "Every edge once, int32 (e, 2), (a, b) with a < b, rows ascending.", NULL},
    {"stats", (getter)tri_stats, NULL,
     "A new dict of the run's statistics (fdt_result_stats).", NULL},
    {"hash", (getter)tri_hash, NULL,
     "The canonical hash of the tet set as 16 hex digits, as `frontdt --hash` "
     "prints it.", NULL},
    {NULL, NULL, NULL, NULL, NULL},
};

/* A new 1-D or 2-D array holding a copy of rows x cols items at data. */
static PyObject *copy_array(const void *data, npy_intp rows, npy_intp cols, int type,
                            size_t item)
{
    npy_intp dims[2] = {rows, cols};
    PyObject *a = PyArray_SimpleNew(cols ? 2 : 1, dims, type);
    if (a && rows)
        memcpy(PyArray_DATA((PyArrayObject *)a), data,
               (size_t)rows * (size_t)(cols ? cols : 1) * item);
    return a;
}

/* An array of what the cells computed, or None for what they left out
 * (fdt_voronoi_options.skip: data NULL). */
static PyObject *copy_or_none(const void *data, npy_intp rows, npy_intp cols, int type,
                              size_t item)
{
    if (data)
        return copy_array(data, rows, cols, type, item);
    Py_INCREF(Py_None);
    return Py_None;
}

/* Triangulation.voronoi(box=None, centroids=True, densities=True): the
 * cells (fdt_voronoi_compute) as a dict of new arrays; the neighbours in
 * CSR form; centroids and densities None where not asked for (they are
 * then not computed). */
static PyObject *tri_voronoi(TriObject *self, PyObject *args, PyObject *kw)
{
    static char *kwlist[] = {"box", "centroids", "densities", NULL};
    PyObject *box_obj = Py_None;
    int centroids = 1, densities = 1;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "|Opp:voronoi", kwlist, &box_obj, &centroids,
                                     &densities))
        return NULL;
    fdt_voronoi_options o;
    fdt_default_voronoi_options(&o);
    o.neighbors = 1;
    o.skip = (centroids ? 0 : FDT_CELLS_NO_CENTROIDS) | (densities ? 0 : FDT_CELLS_NO_DENSITIES);
    if (box_obj != Py_None) {
        PyArrayObject *b = (PyArrayObject *)PyArray_FROMANY(
            box_obj, NPY_DOUBLE, 1, 1, NPY_ARRAY_C_CONTIGUOUS | NPY_ARRAY_ALIGNED);
        if (!b)
            return NULL;
        if (PyArray_DIM(b, 0) != 6) {
            Py_DECREF(b);
            PyErr_SetString(PyExc_ValueError,
                            "box must be (xmin, ymin, zmin, xmax, ymax, zmax)");
            return NULL;
        }
        memcpy(o.box, PyArray_DATA(b), sizeof o.box);
        o.box_given = 1;
        Py_DECREF(b);
    }
    const double *xyz = PyArray_DATA(self->points);
    size_t n = (size_t)PyArray_DIM(self->points, 0);
    fdt_voronoi *v = NULL;
    char diag[512];
    int err;
    Py_BEGIN_ALLOW_THREADS /* r is only read */
    err = fdt_voronoi_compute(self->r, xyz, n, &o, &v, diag, sizeof diag);
    Py_END_ALLOW_THREADS
    if (err)
        return raise_fdt(err, diag);
    PyObject *d = PyDict_New();
    npy_intp *ptr = PyMem_Malloc((n + 1) * sizeof *ptr);
    if (!d || !ptr)
        goto nomem;
    ptr[0] = 0;
    for (size_t i = 0; i < n; i++)
        ptr[i + 1] = ptr[i] + fdt_voronoi_num_faces(v)[i];
    PyObject *nb = PyArray_SimpleNew(1, &ptr[n], NPY_INT32);
    PyObject *fa = PyArray_SimpleNew(1, &ptr[n], NPY_DOUBLE);
    if (nb && fa)
        for (size_t i = 0; i < n; i++) {
            size_t cnt;
            const fdt_vid *ids;
            const double *ar;
            (void)fdt_voronoi_neighbors(v, (fdt_vid)i, &cnt, &ids, &ar);
            memcpy((int32_t *)PyArray_DATA((PyArrayObject *)nb) + ptr[i], ids, cnt * sizeof *ids);
            memcpy((double *)PyArray_DATA((PyArrayObject *)fa) + ptr[i], ar, cnt * sizeof *ar);
        }
    npy_intp nn = (npy_intp)n;
    struct { const char *key; PyObject *val; } items[] = {
        {"volumes", copy_array(fdt_voronoi_volumes(v), nn, 0, NPY_DOUBLE, sizeof(double))},
        {"areas", copy_array(fdt_voronoi_areas(v), nn, 0, NPY_DOUBLE, sizeof(double))},
        {"centroids", copy_or_none(fdt_voronoi_centroids(v), nn, 3, NPY_DOUBLE, sizeof(double))},
        {"num_faces", copy_array(fdt_voronoi_num_faces(v), nn, 0, NPY_INT32, sizeof(int32_t))},
        {"densities", copy_or_none(fdt_voronoi_densities(v), nn, 0, NPY_DOUBLE, sizeof(double))},
        {"flags", copy_array(fdt_voronoi_flags(v), nn, 0, NPY_UINT8, 1)},
        {"neighbor_ptr", copy_array(ptr, nn + 1, 0, NPY_INTP, sizeof(npy_intp))},
        {"neighbors", nb},
        {"face_areas", fa},
    };
    int bad = 0;
    for (size_t k = 0; k < sizeof items / sizeof items[0]; k++) {
        if (!items[k].val || PyDict_SetItemString(d, items[k].key, items[k].val) < 0)
            bad = 1;
        Py_XDECREF(items[k].val);
    }
    PyMem_Free(ptr);
    fdt_voronoi_free(&v);
    if (bad) {
        Py_DECREF(d);
        return PyErr_Occurred() ? NULL : PyErr_NoMemory();
    }
    return d;
nomem:
    Py_XDECREF(d);
    PyMem_Free(ptr);
    fdt_voronoi_free(&v);
    return PyErr_NoMemory();
}

/* Triangulation.find_simplex(q, bruteforce=False, tol=None)-like: the tet
 * holding each query (fdt_locate), -1 outside; with bary=True also the
 * barycentric coordinates. */
static PyObject *tri_find_simplex(TriObject *self, PyObject *args, PyObject *kw)
{
    static char *kwlist[] = {"q", "bary", NULL};
    PyObject *qo;
    int want_bary = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "O|p:find_simplex", kwlist, &qo, &want_bary))
        return NULL;
    PyArrayObject *q = points_array(qo);
    if (!q)
        return NULL;
    npy_intp nq = PyArray_DIM(q, 0), d4[2] = {nq, 4};
    PyObject *tet = PyArray_SimpleNew(1, &nq, NPY_INT64);
    PyObject *bary = want_bary ? PyArray_SimpleNew(2, d4, NPY_DOUBLE) : NULL;
    if (!tet || (want_bary && !bary)) {
        Py_XDECREF(tet);
        Py_XDECREF(bary);
        Py_DECREF(q);
        return NULL;
    }
    const double *xyz = PyArray_DATA(self->points);
    size_t n = (size_t)PyArray_DIM(self->points, 0);
    int err;
    Py_BEGIN_ALLOW_THREADS /* r keeps neighbours: only read */
    err = fdt_locate(self->r, xyz, n, PyArray_DATA(q), (size_t)nq,
                     PyArray_DATA((PyArrayObject *)tet),
                     bary ? PyArray_DATA((PyArrayObject *)bary) : NULL, 0);
    Py_END_ALLOW_THREADS
    Py_DECREF(q);
    if (err) {
        Py_DECREF(tet);
        Py_XDECREF(bary);
        return raise_fdt(err, "locating the queries");
    }
    if (!bary)
        return tet;
    return Py_BuildValue("NN", tet, bary);
}

/* fdt_interpolate's methods, in the enum's order (pick). */
static const char *method_choice(int i)
{
    static const char *const names[] = {"linear", "natural", NULL};
    return names[i];
}

/* Triangulation.interpolate(values, q, method="natural") (fdt_interpolate). */
static PyObject *tri_interpolate(TriObject *self, PyObject *args, PyObject *kw)
{
    static char *kwlist[] = {"values", "q", "method", NULL};
    PyObject *vo, *qo;
    const char *method_s = "natural";
    if (!PyArg_ParseTupleAndKeywords(args, kw, "OO|s:interpolate", kwlist, &vo, &qo, &method_s))
        return NULL;
    int m = pick("method", method_s, method_choice);
    if (m < 0)
        return NULL;
    size_t n = (size_t)PyArray_DIM(self->points, 0);
    PyArrayObject *v = (PyArrayObject *)PyArray_FROMANY(
        vo, NPY_DOUBLE, 1, 2, NPY_ARRAY_C_CONTIGUOUS | NPY_ARRAY_ALIGNED | NPY_ARRAY_ENSURECOPY);
    if (!v)
        return NULL;
    if ((size_t)PyArray_DIM(v, 0) != n || (PyArray_NDIM(v) == 2 && PyArray_DIM(v, 1) < 1)) {
        Py_DECREF(v);
        PyErr_Format(PyExc_ValueError, "values must have one row a point (%zu), got %zd", n,
                     (Py_ssize_t)PyArray_DIM(v, 0));
        return NULL;
    }
    PyArrayObject *q = points_array(qo);
    if (!q) {
        Py_DECREF(v);
        return NULL;
    }
    size_t nv = PyArray_NDIM(v) == 2 ? (size_t)PyArray_DIM(v, 1) : 1;
    npy_intp dims[2] = {PyArray_DIM(q, 0), (npy_intp)nv};
    PyObject *out = PyArray_SimpleNew(PyArray_NDIM(v), dims, NPY_DOUBLE);
    if (!out) {
        Py_DECREF(v);
        Py_DECREF(q);
        return NULL;
    }
    const double *xyz = PyArray_DATA(self->points);
    char diag[512];
    int err;
    Py_BEGIN_ALLOW_THREADS
    err = fdt_interpolate(self->r, xyz, n, PyArray_DATA(v), nv, PyArray_DATA(q),
                          (size_t)PyArray_DIM(q, 0), (fdt_interp)m, 0,
                          PyArray_DATA((PyArrayObject *)out), diag, sizeof diag);
    Py_END_ALLOW_THREADS
    Py_DECREF(v);
    Py_DECREF(q);
    if (err) {
        Py_DECREF(out);
        return raise_fdt(err, diag);
    }
    return out;
}

static PyMethodDef tri_methods[] = {
    {"check", (PyCFunction)tri_check, METH_NOARGS,
     "check()\n--\n\nVerifies exactly that the mesh is the Delaunay "
     "tetrahedralization of the points (fdt_check; a periodic one's: fdt_check_periodic); "
     "raises CheckError if not."},
    {"voronoi", (PyCFunction)(void (*)(void))tri_voronoi, METH_VARARGS | METH_KEYWORDS,
     "voronoi(box=None, centroids=True, densities=True)\n--\n\nEach point's Voronoi cell "
     "clipped by box (xmin, ymin, zmin, xmax, ymax, zmax; None: the points' bounding box), "
     "as a dict of arrays: volumes, areas, centroids (n, 3; None with centroids=False, "
     "which also leaves them uncomputed: faster), num_faces, densities (DTFE; None with "
     "densities=False), flags (1 "
     "clipped, 2 hull, 4 merged duplicate), and the neighbours in CSR form: "
     "neighbors[neighbor_ptr[i]:neighbor_ptr[i+1]] (walls -1..-6) with face_areas "
     "alongside. The same bits for every thread count and input order. A periodic "
     "triangulation's cells are in its own box (box None, or that box), wrapped on its "
     "periodic axes and cut by the box's sides across the others. The GIL is "
     "released while it runs."},
    {"find_simplex", (PyCFunction)(void (*)(void))tri_find_simplex, METH_VARARGS | METH_KEYWORDS,
     "find_simplex(q, bary=False)\n--\n\nThe index of a tet holding each query of the (k, 3) "
     "array-like q (int64, -1 outside the hull), by a walk with exact predicates; with "
     "bary=True a tuple (indices, (k, 4) barycentric coordinates in the order of the tet's "
     "vertices). A periodic triangulation's queries may lie anywhere: each is wrapped into "
     "the box first. The GIL is released while it runs."},
    {"interpolate", (PyCFunction)(void (*)(void))tri_interpolate, METH_VARARGS | METH_KEYWORDS,
     "interpolate(values, q, method='natural')\n--\n\nInterpolates values given at the points "
     "(shape (n,) or (n, k)) at the queries q: 'natural' (Sibson's natural-neighbour "
     "coordinates) or 'linear' (barycentric in the tet holding the query). NaN outside the "
     "hull ('natural': on it too); a query at a point gets that point's values. A periodic "
     "triangulation's queries may lie anywhere: each is wrapped into the box first. The GIL "
     "is released while it runs."},
    {"vertex_neighbors", (PyCFunction)tri_vertex_neighbors, METH_O,
     "vertex_neighbors(v)\n--\n\nThe Delaunay neighbours of point v, int32, "
     "ascending (a new array; empty for a duplicate merged into another)."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject TriType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "frontdt.Triangulation",
    .tp_basicsize = sizeof(TriObject),
    .tp_dealloc = (destructor)tri_dealloc,
    .tp_repr = (reprfunc)tri_repr,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "The Delaunay tetrahedralization returned by frontdt.delaunay().",
    .tp_methods = tri_methods,
    .tp_getset = tri_getset,
};

/* ------------------------------------------------------------ delaunay */

/* fdt_mode's names, in its order (pick). */
static const char *mode_choice(int i)
{
    static const char *const names[] = {"auto", "serial", "shared", "message", NULL};
    return names[i];
}

/* fdt_search's names: the library's table (fdt_search_name). */
static const char *search_choice(int i)
{
    return fdt_search_name((fdt_search)i);
}

static PyObject *py_delaunay(PyObject *mod, PyObject *args, PyObject *kw)
{
    (void)mod;
    static char *kwlist[] = {"points", "threads", "mode", "search", "periodic", "box", NULL};
    PyObject *obj, *threads_obj = Py_None, *box_obj = Py_None;
    const char *mode_s = "auto", *search_s = "auto", *periodic_s = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "O|OsszO:delaunay", kwlist, &obj,
                                     &threads_obj, &mode_s, &search_s, &periodic_s, &box_obj))
        return NULL;
    fdt_settings s;
    fdt_default_settings(&s);
    /* periodic="x,z" with box=(xmin, ymin, zmin, xmax, ymax, zmax) */
    for (const char *q = periodic_s; q && *q; q++) {
        const char *ax = strchr("xyz", *q);
        if (*q == ',')
            continue;
        if (!ax || (s.periodic >> (ax - "xyz") & 1)) {
            PyErr_Format(PyExc_ValueError, "periodic takes axes x, y, z once each "
                         "('x,z', 'xyz'), got '%s'", periodic_s);
            return NULL;
        }
        s.periodic |= 1u << (ax - "xyz");
    }
    if ((s.periodic != 0) != (box_obj != Py_None)) {
        PyErr_SetString(PyExc_ValueError, s.periodic ? "periodic needs box=(xmin, ymin, zmin, "
                        "xmax, ymax, zmax): the periods" : "box needs periodic (the axes)");
        return NULL;
    }
    if (s.periodic) {
        PyObject *seq = PySequence_Fast(box_obj, "box must be a sequence of 6 numbers");
        if (!seq)
            return NULL;
        int ok = PySequence_Fast_GET_SIZE(seq) == 6;
        for (int i = 0; ok && i < 6; i++) {
            s.periodic_box[i] = PyFloat_AsDouble(PySequence_Fast_GET_ITEM(seq, i));
            ok = !(s.periodic_box[i] == -1.0 && PyErr_Occurred());
        }
        Py_DECREF(seq);
        if (!ok) {
            if (!PyErr_Occurred())
                PyErr_SetString(PyExc_ValueError, "box must be a sequence of 6 numbers");
            return NULL;
        }
    }
    int m = pick("mode", mode_s, mode_choice);
    int se = m < 0 ? -1 : pick("search", search_s, search_choice);
    if (m < 0 || se < 0)
        return NULL;
    /* the names come in the enums' order */
    s.mode = (fdt_mode)m;
    s.search = (fdt_search)se;
    if (threads_obj != Py_None) {
        long t = PyLong_AsLong(threads_obj);
        if (t == -1 && PyErr_Occurred())
            return NULL;
        if (t < 1 || t > 1024) {
            PyErr_Format(PyExc_ValueError, "threads must be None or 1 to 1024, got %ld", t);
            return NULL;
        }
        s.n_threads = (int)t;
    }
    s.neighbors = !s.periodic; /* a periodic mesh has none yet (issue 33) */
    cancel_state cs = {mono_s() + 0.25};
    s.progress = progress_cb;
    s.progress_user = &cs;

    PyArrayObject *pts = points_array(obj);
    if (!pts)
        return NULL;
    TriObject *self = PyObject_New(TriObject, &TriType);
    if (!self) {
        Py_DECREF(pts);
        return NULL;
    }
    self->r = NULL;
    self->points = pts;
    self->hash = 0;
    self->lock = PyThread_allocate_lock();
    if (!self->lock) {
        Py_DECREF(self);
        return PyErr_NoMemory();
    }

    fdt_context *ctx = NULL;
    int err = fdt_open(&ctx, &s);
    if (err) {
        Py_DECREF(self);
        return raise_fdt(err, "invalid settings");
    }
    const double *xyz = PyArray_DATA(pts);
    size_t n = (size_t)PyArray_DIM(pts, 0);
    fdt_result *r = NULL;
    Py_BEGIN_ALLOW_THREADS
    err = fdt_triangulate(ctx, xyz, n, &r);
    if (!err)
        err = fdt_result_hash(r, &self->hash); /* sorts first */
    Py_END_ALLOW_THREADS
    self->r = r;
    if (err) {
        raise_fdt(err, fdt_context_diagnostic(ctx));
        fdt_close(&ctx);
        Py_DECREF(self);
        return NULL;
    }
    fdt_close(&ctx);
    return (PyObject *)self;
}

/* frontdt.check(points, simplices, neighbors=None) on any arrays. */
static PyObject *py_check(PyObject *mod, PyObject *args, PyObject *kw)
{
    (void)mod;
    static char *kwlist[] = {"points", "simplices", "neighbors", NULL};
    PyObject *po, *so, *no = Py_None;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "OO|O:check", kwlist, &po, &so, &no))
        return NULL;
    PyArrayObject *p = points_array(po), *t = NULL, *nb = NULL;
    PyObject *res = NULL;
    if (!p)
        return NULL;
    t = (PyArrayObject *)PyArray_FROMANY(so, NPY_INT32, 2, 2,
                                         NPY_ARRAY_C_CONTIGUOUS | NPY_ARRAY_ALIGNED |
                                             NPY_ARRAY_ENSURECOPY);
    if (!t)
        goto done;
    if (PyArray_DIM(t, 1) != 4) {
        PyErr_SetString(PyExc_ValueError, "simplices must be an (m, 4) integer array");
        goto done;
    }
    if (no != Py_None) {
        nb = (PyArrayObject *)PyArray_FROMANY(no, NPY_INT64, 2, 2,
                                              NPY_ARRAY_C_CONTIGUOUS | NPY_ARRAY_ALIGNED |
                                                  NPY_ARRAY_ENSURECOPY);
        if (!nb)
            goto done;
        if (PyArray_DIM(nb, 0) != PyArray_DIM(t, 0) || PyArray_DIM(nb, 1) != 4) {
            PyErr_SetString(PyExc_ValueError, "neighbors must have the shape of simplices");
            goto done;
        }
    }
    res = run_check(PyArray_DATA(p), (size_t)PyArray_DIM(p, 0), PyArray_DATA(t),
                    (size_t)PyArray_DIM(t, 0), nb ? PyArray_DATA(nb) : NULL);
done:
    Py_DECREF(p);
    Py_XDECREF(t);
    Py_XDECREF(nb);
    return res;
}

static PyMethodDef module_methods[] = {
    {"delaunay", (PyCFunction)(void (*)(void))py_delaunay, METH_VARARGS | METH_KEYWORDS,
     "delaunay(points, threads=None, mode='auto', search='auto', periodic=None, box=None)\n--\n\n"
     "The exact Delaunay tetrahedralization of an (n, 3) array-like of points.\n\n"
     "threads: None for one per physical core, or 1 to 1024; mode: 'auto', "
     "'serial', 'shared' or 'message'; search: 'auto', 'kd' or 'mesh' (as the "
     "CLI's --mode, -t and --search). periodic: the periodic axes ('x,z', 'xyz'), "
     "with box=(xmin, ymin, zmin, xmax, ymax, zmax) their periods: the mesh of the "
     "periodic point set, each tet once, its image offsets in .offsets (as the "
     "CLI's --periodic). The GIL is released while it runs. "
     "Raises ValueError for NaN/Inf, fewer than 4 distinct points or all "
     "coplanar (with the library's diagnostic naming the point), MemoryError, "
     "RuntimeError for other failures."},
    {"check", (PyCFunction)(void (*)(void))py_check, METH_VARARGS | METH_KEYWORDS,
     "check(points, simplices, neighbors=None)\n--\n\n"
     "Verifies exactly that simplices (and neighbors, if given) are the "
     "Delaunay tetrahedralization of points (fdt_check), as frontdt breaks "
     "ties; raises CheckError with the reason if not."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef moduledef = {
    PyModuleDef_HEAD_INIT, "frontdt._frontdt",
    "The C extension of the frontdt package (include/frontdt.h).", -1,
    module_methods, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__frontdt(void);
PyMODINIT_FUNC PyInit__frontdt(void)
{
    import_array();
    if (PyType_Ready(&TriType) < 0)
        return NULL;
    PyObject *m = PyModule_Create(&moduledef);
    if (!m)
        return NULL;
    CheckError = PyErr_NewExceptionWithDoc(
        "frontdt.CheckError",
        "fdt_check found that a mesh is not the Delaunay tetrahedralization.",
        PyExc_RuntimeError, NULL);
    if (!CheckError) {
        Py_DECREF(m);
        return NULL;
    }
    /* PyModule_AddObject steals a reference on success only: give it one
     * of its own each time, and drop it where the call failed; the static
     * CheckError keeps the reference made above. */
    Py_INCREF(CheckError);
    if (PyModule_AddObject(m, "CheckError", CheckError) < 0) {
        Py_DECREF(CheckError);
        Py_DECREF(m);
        return NULL;
    }
    Py_INCREF(&TriType);
    if (PyModule_AddObject(m, "Triangulation", (PyObject *)&TriType) < 0) {
        Py_DECREF(&TriType);
        Py_DECREF(m);
        return NULL;
    }
    if (PyModule_AddStringConstant(m, "__version__", fdt_version()) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
