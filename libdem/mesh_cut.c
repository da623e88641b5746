/* Which particle a mesh cuts (deeper than insert_overlap_ratio of its radius): the check when
 * a mesh is added to particles (mesh.c) and particles to meshes (particles.c). */
#include "triangle.h"
#include "cell_grid.h"
#include "internal.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Particle k (of n at x, r) that mesh m cuts, or -1. The particles are hashed into a grid
 * of cells of the largest diameter; each triangle checks the cells its inflated box covers. */
int64_t dem_mesh_first_cut(const dem_domain *d, const mesh_wall *m, int64_t n, const double *x, const double *r)
{
    if (n == 0) return -1;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, rmax = 0.0;
    for (int64_t i = 0; i < n; i++) {
        rmax = fmax(rmax, r[i]);
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], x[3 * i + a]);
            hi[a] = fmax(hi[a], x[3 * i + a]);
        }
    }
    cell_grid g;
    double cs = 2.0 * rmax;
    for (;;) { /* at most ~2 cells per particle */
        int64_t total = 1;
        for (int a = 0; a < 3; a++) {
            double c = floor((hi[a] - lo[a]) / cs) + 1.0;
            g.n[a] = c > 1e6 ? 1000000 : (int)c;
            total *= g.n[a];
        }
        if (total <= 2 * n + 64) break;
        cs *= 1.5;
    }
    for (int a = 0; a < 3; a++) {
        g.lo[a] = lo[a];
        g.size[a] = cs;
    }
    const int *nc = g.n;
    int grid = cell_grid_alloc(&g, n); /* without memory for the grid: check every particle */
    if (grid)
        for (int64_t i = n - 1; i >= 0; i--)
            cell_grid_push(&g, i, cell_index(nc, cell_grid_coord(&g, x[3 * i], 0), cell_grid_coord(&g, x[3 * i + 1], 1),
                                             cell_grid_coord(&g, x[3 * i + 2], 2)));
    int64_t found = -1;
    const double keep = 1.0 - d->def.insert_overlap_ratio;
    for (int64_t t = 0; t < m->nt && found < 0; t++) {
        const int32_t *tv = m->tri + 3 * t;
        const double *A = m->x + 3 * tv[0], *B = m->x + 3 * tv[1], *C = m->x + 3 * tv[2];
        int c0[3], c1[3];
        int outside = 0;
        for (int a = 0; a < 3; a++) {
            double tlo = fmin(A[a], fmin(B[a], C[a])) - rmax, thi = fmax(A[a], fmax(B[a], C[a])) + rmax;
            if (thi < lo[a] || tlo > hi[a]) outside = 1;
            c0[a] = cell_grid_coord(&g, tlo, a);
            c1[a] = cell_grid_coord(&g, thi, a);
        }
        if (outside) continue;
        if (!grid) {
            for (int64_t i = 0; i < n && found < 0; i++) {
                double q[3];
                tri_closest_point(x + 3 * i, A, B, C, q);
                if (tri_dist2(x + 3 * i, q) < keep * keep * r[i] * r[i]) found = i;
            }
            continue;
        }
        for (int cz = c0[2]; cz <= c1[2]; cz++)
            for (int cy = c0[1]; cy <= c1[1]; cy++)
                for (int cx = c0[0]; cx <= c1[0]; cx++)
                    for (int64_t i = g.head[cell_index(nc, cx, cy, cz)]; i >= 0; i = g.next[i]) {
                        double q[3];
                        tri_closest_point(x + 3 * i, A, B, C, q);
                        if (tri_dist2(x + 3 * i, q) < keep * keep * r[i] * r[i] && (found < 0 || i < found)) found = i;
                    }
    }
    cell_grid_free(&g);
    return found;
}

int64_t dem_meshes_cut_particles(const dem_domain *d, int64_t n, const double *x, const double *r, int *which_mesh)
{
    for (int k = 0; k < d->n_meshes; k++) {
        int64_t i = dem_mesh_first_cut(d, &d->meshes[k], n, x, r);
        if (i >= 0) {
            *which_mesh = k;
            return i;
        }
    }
    return -1;
}
