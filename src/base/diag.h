/* A diagnostic written into the caller's buffer: how the library says
 * where and why a call failed without printing (include/frontdt.h: no
 * output unasked). Nothing is written when diag is NULL or size is 0. */
#ifndef FDT_DIAG_H
#define FDT_DIAG_H

#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>

#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static inline void fdt_diag(char *diag, size_t size, const char *fmt, ...)
{
    if (!diag || !size)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(diag, size, fmt, ap);
    va_end(ap);
}

#endif
