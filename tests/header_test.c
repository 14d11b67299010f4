/* The public header must compile alone under -std=c11 -pedantic -Werror. */
#include "frontdt.h"

#include <stddef.h>

/* The ABI rule of the header: every struct that may grow starts with its
 * size (tests/test_api.c checks what the library does with it). */
_Static_assert(offsetof(fdt_settings, struct_size) == 0, "struct_size first");
_Static_assert(offsetof(fdt_stats, struct_size) == 0, "struct_size first");
_Static_assert(offsetof(fdt_thread_stats, struct_size) == 0, "struct_size first");
_Static_assert(offsetof(fdt_read_options, struct_size) == 0, "struct_size first");
_Static_assert(offsetof(fdt_write_options, struct_size) == 0, "struct_size first");

int main(void)
{
    fdt_settings s;
    (void)s;
    return FDT_OK;
}
