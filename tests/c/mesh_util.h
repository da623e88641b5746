/* Mesh builders for the tests: triangulated rectangles and boxes. */
#ifndef MESH_UTIL_H
#define MESH_UTIL_H

#include "test_util.h"

/* A flat rectangle [x0, x1] x [y0, y1] at height z, nx x ny squares each split along the same
 * diagonal, so interior vertices are shared by six triangles. Caller frees *v and *t. */
static inline void grid_rectangle(double x0, double x1, double y0, double y1, double z, int nx, int ny, double **v,
                                  int64_t *nv, int32_t **t, int64_t *nt)
{
    *nv = (int64_t)(nx + 1) * (ny + 1);
    *nt = 2 * (int64_t)nx * ny;
    *v = malloc((size_t)*nv * 3 * sizeof(double));
    *t = malloc((size_t)*nt * 3 * sizeof(int32_t));
    for (int j = 0; j <= ny; j++)
        for (int i = 0; i <= nx; i++) {
            double *p = *v + 3 * (j * (nx + 1) + i);
            p[0] = x0 + (x1 - x0) * i / nx;
            p[1] = y0 + (y1 - y0) * j / ny;
            p[2] = z;
        }
    int32_t *q = *t;
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            int32_t a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, e = c + 1;
            q[0] = a; q[1] = b; q[2] = e;
            q[3] = a; q[4] = e; q[5] = c;
            q += 6;
        }
}

/* Adds grid_rectangle(...) as a mesh wall of the given material; returns its handle. */
static inline dem_mesh_wall add_grid_mesh(dem_domain *d, double x0, double x1, double y0, double y1, double z, int nx,
                                          int ny, dem_material material)
{
    double *v;
    int32_t *t;
    int64_t nv, nt;
    grid_rectangle(x0, x1, y0, y1, z, nx, ny, &v, &nv, &t, &nt);
    dem_mesh_def md = dem_default_mesh_def();
    md.material = material;
    dem_mesh_wall mesh = {-1};
    assert_ok(dem_mesh_wall_add(d, nv, v, nt, t, &md, &mesh));
    free(v);
    free(t);
    return mesh;
}

/* An open box (floor + four sides, no lid) [0, L] x [0, L] x [0, H] as one mesh; each face
 * split into n x n squares (n = 1: two triangles per face). */
static inline dem_mesh_wall add_open_box(dem_domain *d, double L, double H, int n, dem_material material)
{
    int64_t total_v = 0, total_t = 0;
    double *V = malloc((size_t)5 * (n + 1) * (n + 1) * 3 * sizeof(double));
    int32_t *T = malloc((size_t)5 * 2 * n * n * 3 * sizeof(int32_t));
    for (int face = 0; face < 5; face++) {
        double *v;
        int32_t *t;
        int64_t nv, nt;
        grid_rectangle(0, 1, 0, 1, 0, n, n, &v, &nv, &t, &nt);
        for (int64_t k = 0; k < nv; k++) { /* map the unit square onto the face */
            double s = v[3 * k], u = v[3 * k + 1], *p = V + 3 * (total_v + k);
            switch (face) {
            case 0: p[0] = s * L; p[1] = u * L; p[2] = 0; break;
            case 1: p[0] = 0; p[1] = s * L; p[2] = u * H; break;
            case 2: p[0] = L; p[1] = s * L; p[2] = u * H; break;
            case 3: p[0] = s * L; p[1] = 0; p[2] = u * H; break;
            default: p[0] = s * L; p[1] = L; p[2] = u * H; break;
            }
        }
        for (int64_t k = 0; k < 3 * nt; k++) T[3 * total_t + k] = (int32_t)(t[k] + total_v);
        total_v += nv;
        total_t += nt;
        free(v);
        free(t);
    }
    dem_mesh_def md = dem_default_mesh_def();
    md.material = material;
    dem_mesh_wall mesh = {-1};
    assert_ok(dem_mesh_wall_add(d, total_v, V, total_t, T, &md, &mesh));
    free(V);
    free(T);
    return mesh;
}

#endif
