/* Effect: simplified JKR cohesion (LIGGGHTS "sjkr"). F = -k_c A, attractive, with A the
 * contact area: the lens of two overlapping spheres, or pi (R^2 - r^2) against a wall
 * (r = centre-to-wall distance). k_c is a cohesion energy density (J/m^3). */
#include "internal.h"
#include <math.h>

/* The force for contact distance d and radii ri, rj (rj = 0: a wall), written once for both
 * kernels; branch-free (both areas computed, one kept), so the batch loop vectorises. */
static inline double sjkr_force(double kc, double d, double ri, double rj)
{
    /* circle where the two spheres intersect: a^2 = R_i^2 - s^2, s = (d^2 + R_i^2 - R_j^2)/(2d) */
    const double s = (d * d + ri * ri - rj * rj) / (2.0 * d);
    const double a2 = ri * ri - s * s;
    const double lens = a2 > 0.0 ? DEM_PI * a2 : 0.0;
    const double disk = DEM_PI * (ri * ri - d * d); /* against a wall, d the centre-to-wall distance */
    return -kc * (rj > 0.0 ? lens : disk);
}

static double sjkr_normal_force(const dem_effect_contact *c, const double *params)
{
    return sjkr_force(params[0], c->distance, c->radius_i, c->radius_j);
}

static void sjkr_normal_force_batch(const dem_effect_batch *b, const double *params, double *fn_total)
{
    const double kc = params[0];
    const double *restrict d = b->distance, *restrict ri = b->radius_i, *restrict rj = b->radius_j;
    for (int q = 0; q < b->m; q++) fn_total[q] += sjkr_force(kc, d[q], ri[q], rj[q]);
}

const dem_effect_desc dem_effect_cohesion_sjkr = {
    .name = "cohesion_sjkr",
    .summary = "simplified JKR cohesion: attractive normal force k_c * contact area",
    .n_params = 1,
    .params = {{.name = "cohesion_energy_density", .unit = "J/m^3", .neutral = 0.0, .min = 0.0, .max = 1e12}},
    .normal_force = sjkr_normal_force,
    .normal_force_batch = sjkr_normal_force_batch,
};
