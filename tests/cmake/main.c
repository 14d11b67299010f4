/*
 * A library user (tests/cmake_package.sh builds it with CMake's
 * find_package and with pkg-config): triangulates the points of the .xyz
 * file named by argv[1] (x y z per line, nothing else) and prints the tet
 * count and the canonical hash, which the script compares with the CLI's.
 */
#include <frontdt.h>

#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
    if (argc != 2)
        return 2;
    FILE *f = fopen(argv[1], "r");
    if (!f)
        return 2;
    double xyz[3 * 64];
    size_t n = 0;
    while (n < 64 && fscanf(f, "%lf %lf %lf", &xyz[3 * n], &xyz[3 * n + 1], &xyz[3 * n + 2]) == 3)
        n++;
    fclose(f);
    fdt_settings s;
    fdt_default_settings(&s);
    fdt_context *ctx;
    fdt_result *r;
    uint64_t h = 0;
    if (fdt_open(&ctx, &s) != FDT_OK)
        return 1;
    int e = fdt_triangulate(ctx, xyz, n, &r);
    if (e != FDT_OK) {
        fprintf(stderr, "%s\n", fdt_context_diagnostic(ctx));
        return 1;
    }
    if (fdt_result_hash(r, &h) != FDT_OK)
        return 1;
    printf("tets: %zu\nhash: %016" PRIx64 "\nversion: %s\n", fdt_result_num_tets(r), h,
           fdt_version());
    fdt_result_free(&r);
    fdt_close(&ctx);
    return 0;
}
