/* Restitution correction. With Hertz damping gamma = c sqrt(S_n m*) the equation of a
 * head-on impact, scaled by the maximum-overlap and velocity scales, becomes
 *     x'' = -max(0, x^(3/2) + zeta x^(1/4) x'),   x(0) = 0, x'(0) = 1,   zeta = c sqrt(3/2),
 * independent of E, R, m and impact speed. Its exit speed is the delivered restitution.
 * The usual c = -2 sqrt(5/6) beta(e) is exact only without the clip at zero (no attraction);
 * with the clip it delivers too high an e. We invert e(c) of the clipped equation
 * numerically (bisection), so the delivered e is the requested one at any impact speed. */
#include "internal.h"
#include <math.h>

static void rhs(double zeta, double x, double u, double *dx, double *du)
{
    double f = 0.0;
    if (x > 0.0) {
        f = x * sqrt(x) + zeta * sqrt(sqrt(x)) * u;
        if (f < 0.0) f = 0.0;
    }
    *dx = u;
    *du = -f;
}

double dem_restitution_for_damping_factor(double factor)
{
    const double zeta = factor * sqrt(1.5);
    /* Early on x ~ t and the damping term ~ t^(1/4) is not smooth: start with the
     * series solution over a short interval, then RK4 with a fine fixed step. */
    double t0 = 1e-6;
    double x = t0, u = 1.0 - zeta * pow(t0, 1.25) / 1.25;
    const double h = 2e-4;
    for (int it = 0; it < 1000000; it++) {
        double k1x, k1u, k2x, k2u, k3x, k3u, k4x, k4u;
        rhs(zeta, x, u, &k1x, &k1u);
        rhs(zeta, x + 0.5 * h * k1x, u + 0.5 * h * k1u, &k2x, &k2u);
        rhs(zeta, x + 0.5 * h * k2x, u + 0.5 * h * k2u, &k3x, &k3u);
        rhs(zeta, x + h * k3x, u + h * k3u, &k4x, &k4u);
        double xn = x + h / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x);
        double un = u + h / 6.0 * (k1u + 2 * k2u + 2 * k3u + k4u);
        if (xn <= 0.0) return -un; /* force vanishes at x = 0: exit speed */
        x = xn;
        u = un;
        if (u <= 0.0 && x * sqrt(x) + zeta * sqrt(sqrt(x)) * u <= 0.0) return -u; /* clipped: coasts out */
    }
    return 0.0;
}

static double invert(double e)
{
    /* e(c) decreases monotonically from 1 (c = 0) towards 0 (c -> infinity) */
    double lo = 0.0, hi = 1.0;
    while (dem_restitution_for_damping_factor(hi) > e && hi < 1e6) hi *= 2.0;
    for (int it = 0; it < 60 && hi - lo > 1e-13 * hi; it++) {
        double mid = 0.5 * (lo + hi);
        if (dem_restitution_for_damping_factor(mid) > e) lo = mid;
        else hi = mid;
    }
    return 0.5 * (lo + hi);
}

/* The inversion costs ~30 ms; campaigns create many domains with the same few restitution
 * values, so results are kept in a small process-wide cache (exact match on e). The critical
 * section makes it safe for concurrent domains on different threads. */
#define CACHE_SIZE 64
static double cache_e[CACHE_SIZE], cache_factor[CACHE_SIZE];
static int cache_count, cache_next;

double dem_damping_factor_for_restitution(double e)
{
    if (e >= 1.0) return 0.0;
    double factor = -1.0;
#pragma omp critical(dem_restitution_cache)
    for (int k = 0; k < cache_count; k++)
        if (cache_e[k] == e) factor = cache_factor[k];
    if (factor >= 0.0) return factor;
    factor = invert(e);
#pragma omp critical(dem_restitution_cache)
    {
        cache_e[cache_next] = e;
        cache_factor[cache_next] = factor;
        cache_next = (cache_next + 1) % CACHE_SIZE;
        if (cache_count < CACHE_SIZE) cache_count++;
    }
    return factor;
}
