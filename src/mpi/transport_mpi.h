/*
 * The MPI transport of the parallel engine (issue 19; src/par/transport.h):
 * one part per rank, endpoint i is rank i of the communicator. Built only
 * with MPI (meson -Dmpi). Nothing is shared between ranks but these
 * messages (Merriam §4: the iPSC/860's processors shared nothing either).
 */
#ifndef FDT_TRANSPORT_MPI_H
#define FDT_TRANSPORT_MPI_H

#include <mpi.h>

#include "par/transport.h"

/* A transport over a duplicate of comm (so the engine's messages never
 * meet the caller's), for the calling rank, whose endpoint is its rank.
 * Only that endpoint may be used (alloc, post from it, poll, wait); kick is
 * a no-op (one thread a rank). *out is NULL on failure. 0, FDT_ENOMEM or
 * FDT_EINTERNAL (an MPI call failed). */
int fdt_transport_mpi(fdt_transport **out, MPI_Comm comm);

/* Frees the requests of sends still in flight without waiting for them
 * (after an ABORT a receiver may have stopped before taking them; our
 * messages are small, so MPI has sent them eagerly). Call before
 * fdt_transport_destroy when the run failed. */
void fdt_transport_mpi_abandon(fdt_transport *t);

#endif
