/* The public header must compile alone under -std=c11 -pedantic -Werror. */
#include "frontdt.h"

int main(void)
{
    fdt_settings s;
    (void)s;
    return FDT_OK;
}
