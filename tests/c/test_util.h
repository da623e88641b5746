/* Shared helpers for the cmocka tests: a relative/absolute closeness assertion (cmocka
 * 1.1.5 has no double equality) and small domain builders. */
#ifndef TEST_UTIL_H
#define TEST_UTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem/dem.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* |actual - expected| <= atol + rtol |expected|; prints both on failure, and always when
 * DEM_TEST_VERBOSE is set (to see how much margin a tolerance has). */
#define assert_close(actual, expected, rtol, atol)                                                              \
    do {                                                                                                        \
        double a_ = (actual), e_ = (expected);                                                                  \
        double tol_ = (atol) + (rtol) * fabs(e_);                                                               \
        if (getenv("DEM_TEST_VERBOSE"))                                                                         \
            printf("  %s = %.9g, expected %.9g, rel err %.2e (tol %.1e)\n", #actual, a_, e_,                    \
                   e_ != 0 ? fabs(a_ - e_) / fabs(e_) : fabs(a_ - e_), tol_ / (e_ != 0 ? fabs(e_) : 1.0));       \
        if (!(fabs(a_ - e_) <= tol_)) {                                                                         \
            print_error("%s = %.12g, expected %.12g (tol %.3g, rel err %.3g)\n", #actual, a_, e_, tol_,        \
                        e_ != 0 ? fabs(a_ - e_) / fabs(e_) : fabs(a_ - e_));                                   \
            fail();                                                                                             \
        }                                                                                                       \
    } while (0)

#define assert_ok(call)                                                                                         \
    do {                                                                                                        \
        dem_status s_ = (call);                                                                                 \
        if (s_ != DEM_OK) {                                                                                     \
            print_error("%s returned %s\n", #call, dem_status_name(s_));                                        \
            fail();                                                                                             \
        }                                                                                                       \
    } while (0)

/* A closed box [0, L]^3, no gravity, one material with the given constants. */
static inline dem_domain *make_domain(double box, double dt, double E, double e, double mu, dem_material *material)
{
    dem_domain_def def = dem_default_domain_def();
    for (int a = 0; a < 3; a++) {
        def.lo[a] = 0.0;
        def.hi[a] = box;
        def.gravity[a] = 0.0;
    }
    def.dt = dt;
    dem_domain *d = NULL;
    char msg[256];
    if (dem_domain_create(&def, &d, msg, sizeof msg) != DEM_OK) {
        print_error("create failed: %s\n", msg);
        return NULL;
    }
    dem_material_def m = dem_default_material_def();
    m.youngs_modulus = E;
    if (dem_material_create(d, &m, material) != DEM_OK) return NULL;
    dem_pair_def p = dem_default_pair_def();
    p.restitution = e;
    p.friction = mu;
    if (dem_pair_set(d, *material, *material, &p) != DEM_OK) return NULL;
    return d;
}

/* xorshift64: uniform in [0, 1), reproducible across machines (no libc rand). */
static inline double test_urand(uint64_t *state)
{
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    return (double)(*state >> 11) / 9007199254740992.0;
}

/* One sphere of radius r at (c, c, r + gap) falling at speed v onto a floor z >= 0 made
 * of the same material. */
static inline void add_sphere_over_floor(dem_domain *d, dem_material mat, double c, double r, double gap, double v)
{
    dem_plane_wall wall;
    dem_plane_wall_def w = dem_default_plane_wall_def();
    w.material = mat;
    assert_ok(dem_plane_wall_add(d, &w, &wall));
    double pos[3] = {c, c, r + gap}, vel[3] = {0, 0, -v};
    assert_ok(dem_particles_add(d, 1, pos, &r, &mat, vel, NULL, NULL));
}

/* Two spheres of radius r on the z axis through (c, c, c), gap apart, closing at speed v. */
static inline void add_head_on_pair(dem_domain *d, dem_material mat, double c, double r, double gap, double v)
{
    double pos[6] = {c, c, c - r - gap / 2, c, c, c + r + gap / 2};
    double rad[2] = {r, r}, vel[6] = {0, 0, v / 2, 0, 0, -v / 2};
    dem_material mats[2] = {mat, mat};
    assert_ok(dem_particles_add(d, 2, pos, rad, mats, vel, NULL, NULL));
}

/* Effective constants of the seed-000 law for identical materials. */
static inline double e_star_same(double E, double nu) { return E / (2.0 * (1.0 - nu * nu)); }
static inline double sphere_mass(double rho, double r) { return rho * 4.0 / 3.0 * M_PI * r * r * r; }

/* Head-on Hertz closed forms (DESIGN section 3). */
static inline double hertz_max_overlap(double m_eff, double v, double e_star, double r_eff)
{
    return pow(15.0 * m_eff * v * v / (16.0 * e_star * sqrt(r_eff)), 0.4);
}

#endif
