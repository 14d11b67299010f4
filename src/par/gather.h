/*
 * The gather of a parallel run's output: the parts' tets into one mesh in
 * input numbering, neighbours linked across parts (src/par/gather.c).
 */
#ifndef FDT_GATHER_H
#define FDT_GATHER_H

#include "par/state.h"

/* Calling thread, every worker done: offsets, thread 0's buffers grown. */
int fdt_gather_prepare(engine *e);
/* On each worker: its share of the copy. */
void fdt_gather_copy(worker *w);
/* Calling thread, after every copy: the mesh out, neighbours linked. */
int fdt_gather_finish(engine *e, fdt_meshbuf *mb);

#endif