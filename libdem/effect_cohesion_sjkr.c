/* Effect: simplified JKR cohesion (LIGGGHTS "sjkr"). F = -k_c A, attractive, with A the
 * contact area: the lens of two overlapping spheres, or pi (R^2 - r^2) against a wall
 * (r = centre-to-wall distance). k_c is a cohesion energy density (J/m^3). */
#include "internal.h"
#include <math.h>

static double sjkr_normal_force(const dem_effect_contact *c, const double *params)
{
    const double kc = params[0];
    double area;
    if (c->radius_j > 0.0) {
        /* circle where the two spheres intersect: a^2 = R_i^2 - s^2, s = (d^2 + R_i^2 - R_j^2)/(2d) */
        const double d = c->distance, ri = c->radius_i, rj = c->radius_j;
        const double s = (d * d + ri * ri - rj * rj) / (2.0 * d);
        const double a2 = ri * ri - s * s;
        area = a2 > 0.0 ? DEM_PI * a2 : 0.0;
    } else {
        const double r = c->distance, ri = c->radius_i;
        area = DEM_PI * (ri * ri - r * r);
    }
    return -kc * area;
}

const dem_effect_desc dem_effect_cohesion_sjkr = {
    .name = "cohesion_sjkr",
    .summary = "simplified JKR cohesion: attractive normal force k_c * contact area",
    .n_params = 1,
    .params = {{.name = "cohesion_energy_density", .unit = "J/m^3", .neutral = 0.0, .min = 0.0, .max = 1e12}},
    .normal_force = sjkr_normal_force,
};
