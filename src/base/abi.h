/*
 * include/frontdt.h's ABI rule for the option structs that may grow, all
 * of which start with size_t struct_size: a size the library does not know
 * is refused, and nothing is written beyond the size the caller gave.
 */
#ifndef FDT_ABI_H
#define FDT_ABI_H

#include <stddef.h>
#include <string.h>

#include "frontdt.h"

/* Zeroes the struct_size bytes at o and stores struct_size first; known:
 * whether this library accepts that size. An unknown size writes only a 0
 * struct_size (when the caller's bytes hold one), so a later call refuses
 * the struct rather than reading defaults for another layout. */
static inline int fdt_abi_reset(void *o, size_t struct_size, int known)
{
    if (!o)
        return FDT_EINVAL;
    if (!known) {
        if (struct_size >= sizeof struct_size)
            memset(o, 0, sizeof struct_size);
        return FDT_EINVAL;
    }
    memset(o, 0, struct_size);
    memcpy(o, &struct_size, sizeof struct_size);
    return FDT_OK;
}

#endif
