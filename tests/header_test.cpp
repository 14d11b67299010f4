// The public header must compile from C++ too, with C linkage.
#include "frontdt.h"

int main()
{
    fdt_settings s{};
    (void)s;
    return FDT_OK;
}
