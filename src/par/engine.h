/*
 * The per-part step of the parallel engine (src/par/engine.c): a face
 * arrives, a tet is built, a part's loop; and the engine's creation. Its
 * state is src/par/state.h.
 */
#ifndef FDT_ENGINE_H
#define FDT_ENGINE_H

#include "par/protocol.h"
#include "par/state.h"

/* A face of tet `link` of thread `thread` arrives at its owner (us). */
int fdt_eng_face_arrives(worker *w, const uint32_t v[3], int thread, int64_t link, fdt_face *known);
/* Builds tet v, which we own; request: asked for by FACESEND. */
int fdt_eng_build_tet(worker *w, const uint32_t v[4], int request, fdt_face *advanced);
/* Builds tet v asked for by a FACESEND whose link is mtet: the tet's slot
 * in the mesh of every point (engine.gmesh) when the sender read its apex
 * there, -1 otherwise. */
int fdt_eng_build_requested(worker *w, const uint32_t v[4], int64_t mtet);
/* The worker's tables (on its own thread, after pinning). */
int fdt_eng_worker_setup(worker *w);
/* The worker's loop: seeds, messages, faces, until IAMDONE or abort. */
int fdt_eng_worker_loop(worker *w);
/* Engine.park: NODERECV m resumes the face parked in its slot (the walk
 * goes on, or the face is finished). RUN_ON or an error. */
int fdt_eng_resume(worker *w, const fdt_msg *m);
void fdt_eng_worker_free(worker *w);

/* The step the message handlers call back (src/par/protocol.h): every
 * engine's ops. */
extern const fdt_proto_ops fdt_eng_ops;

/* A zeroed engine of n workers (n >= 1), its atomics initialized, e->n
 * and e->ops set; the threaded run (src/par/parallel.c) and an MPI rank (src/mpi/mpi_run.c)
 * fill in the rest. NULL when out of memory. Freed by fdt_eng_delete
 * (the workers' own tables by fdt_eng_worker_free first). */
engine *fdt_eng_new(int n);
void fdt_eng_delete(engine *e);

#endif