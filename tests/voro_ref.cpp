/*
 * voro_ref XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX [periodic[=AXES]] < POINTS > CELLS
 *
 * The reference Voronoi cells (issue 32): voro++ (Debian's libvoro++), each
 * point's cell in a box-shaped container, as voro++ computes it: the box
 * cut by the bisector planes of nearby points. Reads "x y z" lines; writes
 * one line a point, in input order, with 17 digits (voro++'s own command
 * prints 6):
 *   id volume area faces cx cy cz | neighbour area neighbour area ...
 * (centroid absolute; walls are voro++'s -1..-6). Used by
 * tests/voronoi_voro.py only; voro++ is a reference, never in the engine.
 */
#include <voro++/voro++.hh>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <vector>

int main(int argc, char **argv)
{
    double b[6];
    /* periodic: the container periodic in x, y and z; periodic=AXES in
     * those named (x, y, z), walls across the others (issue 33's cells) */
    bool per[3] = {false, false, false};
    bool ok = argc >= 2 && argc <= 3 &&
              std::sscanf(argv[1], "%lf,%lf,%lf,%lf,%lf,%lf", &b[0], &b[1], &b[2], &b[3],
                          &b[4], &b[5]) == 6;
    if (ok && argc == 3) {
        const char *a = argv[2];
        if (!std::strcmp(a, "periodic"))
            per[0] = per[1] = per[2] = true;
        else if (!std::strncmp(a, "periodic=", 9) && a[9])
            for (const char *c = a + 9; *c; c++)
                if (*c >= 'x' && *c <= 'z')
                    per[*c - 'x'] = true;
                else
                    ok = false;
        else
            ok = false;
    }
    if (!ok) {
        std::fprintf(stderr, "usage: voro_ref XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX [periodic[=AXES]] "
                             "< points\n");
        return 1;
    }
    std::vector<double> p;
    double x, y, z;
    while (std::scanf("%lf %lf %lf", &x, &y, &z) == 3) {
        p.push_back(x);
        p.push_back(y);
        p.push_back(z);
    }
    int n = (int)(p.size() / 3);
    // About 5 points a block, as voro++'s own command chooses.
    double vol = (b[3] - b[0]) * (b[4] - b[1]) * (b[5] - b[2]);
    double side = std::cbrt(vol * 5 / (n ? n : 1));
    int nx = (int)((b[3] - b[0]) / side) + 1, ny = (int)((b[4] - b[1]) / side) + 1,
        nz = (int)((b[5] - b[2]) / side) + 1;
    voro::container con(b[0], b[3], b[1], b[4], b[2], b[5], nx, ny, nz, per[0], per[1], per[2], 8);
    for (int i = 0; i < n; i++)
        con.put(i, p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    std::vector<std::vector<char>> line(n);
    voro::c_loop_all vl(con);
    voro::voronoicell_neighbor c;
    std::vector<int> nb;
    std::vector<double> fa;
    std::vector<char *> out(n, nullptr);
    std::vector<size_t> outlen(n, 0);
    if (vl.start())
        do
            if (con.compute_cell(c, vl)) {
                int id = vl.pid();
                double px, py, pz, cx, cy, cz;
                vl.pos(px, py, pz);
                c.centroid(cx, cy, cz);
                c.neighbors(nb);
                c.face_areas(fa);
                FILE *f = open_memstream(&out[id], &outlen[id]);
                std::fprintf(f, "%d %.17g %.17g %d %.17g %.17g %.17g |", id, c.volume(),
                             c.surface_area(), c.number_of_faces(), px + cx, py + cy, pz + cz);
                for (size_t k = 0; k < nb.size(); k++)
                    std::fprintf(f, " %d %.17g", nb[k], fa[k]);
                std::fclose(f);
            }
        while (vl.inc());
    for (int i = 0; i < n; i++) {
        std::printf("%s\n", out[i] ? out[i] : "");
        std::free(out[i]);
    }
    return 0;
}
