/* The packed bed's initial lattice (DESIGN section 10), shared by the benchmarks: simple
 * cubic, spacing 2.2 mm, 1.1 mm from the walls, n_side x n_side x nz spheres of radius 1 mm,
 * velocities uniform in +-0.05 m/s from a fixed LCG (the same bed on every machine). */
#ifndef BENCH_LATTICE_H
#define BENCH_LATTICE_H

#include <stdint.h>
#include <stdlib.h>

#define LATTICE_SPACING 2.2e-3
#define LATTICE_RADIUS 1e-3

/* Fills malloc'ed arrays (caller frees); returns the sphere count. */
static int64_t lattice(int n_side, int nz, dem_material material, double **pos, double **vel, double **rad,
                       dem_material **mats)
{
    const int64_t n = (int64_t)n_side * n_side * nz;
    *pos = malloc(sizeof(double) * 3 * n);
    *vel = malloc(sizeof(double) * 3 * n);
    *rad = malloc(sizeof(double) * n);
    *mats = malloc(sizeof(dem_material) * n);
    uint64_t rng = 42;
    for (int64_t k = 0; k < n; k++) {
        int64_t c[3] = {k % n_side, (k / n_side) % n_side, k / ((int64_t)n_side * n_side)};
        for (int a = 0; a < 3; a++) {
            rng = rng * 6364136223846793005ULL + 1442695040888963407ULL;
            (*pos)[3 * k + a] = 1.1e-3 + LATTICE_SPACING * (double)c[a];
            (*vel)[3 * k + a] = ((double)(rng >> 11) / 9007199254740992.0 - 0.5) * 0.1;
        }
        (*rad)[k] = LATTICE_RADIUS;
        (*mats)[k] = material;
    }
    return n;
}

#endif
