/* Hertz head-on impacts against the closed forms of DESIGN section 3:
 *   d_max = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5),  F_max = (4/3) E* sqrt(R*) d_max^(3/2),
 *   t_c = 2.94328 d_max / v.
 * Elastic (e = 1) and frictionless, so the closed forms are exact for the model; the only
 * error is time discretisation. dt = t_c / 4000: the contact time is counted in whole
 * steps (error <= dt/t_c = 2.5e-4) and the peaks are sampled (error O((dt/t_c)^2)).
 * Tolerance 1e-3 (the issue asks 1 %). */
#include "test_util.h"

static const double R = 1e-3, RHO = 2500, E = 1e8, NU = 0.25;

typedef struct impact { double max_overlap, peak_force, contact_time; } impact;

/* Steps until the contact has ended; wall: sphere 0 on the floor, else spheres 0 and 1. */
static impact run_impact(dem_domain *d, int wall, double dt)
{
    impact r = {0, 0, 0};
    double x[6], f[6];
    int in_contact = 0, ended = 0;
    long steps = 0;
    for (long s = 0; s < 2000000 && !ended; s++) {
        assert_ok(dem_domain_step(d, 1));
        assert_ok(dem_particles_get_positions(d, x, dem_particle_count(d)));
        assert_ok(dem_particles_get_forces(d, f, dem_particle_count(d)));
        double overlap = wall ? R - x[2] : 2 * R - fabs(x[5] - x[2]);
        double fz = fabs(f[2]);
        if (overlap > 0) {
            in_contact = 1;
            steps++;
            if (overlap > r.max_overlap) r.max_overlap = overlap;
            if (fz > r.peak_force) r.peak_force = fz;
        } else if (in_contact) {
            ended = 1;
        }
    }
    assert_true(ended);
    r.contact_time = steps * dt;
    return r;
}

static void check(impact got, double m_eff, double v, double e_star, double r_eff)
{
    double dmax = hertz_max_overlap(m_eff, v, e_star, r_eff);
    double fmax = 4.0 / 3.0 * e_star * sqrt(r_eff) * pow(dmax, 1.5);
    double tc = 2.94328 * dmax / v;
    assert_close(got.max_overlap, dmax, 1e-3, 0);
    assert_close(got.peak_force, fmax, 1e-3, 0);
    assert_close(got.contact_time, tc, 1e-3, 0);
}

static void test_sphere_sphere(void **state)
{
    (void)state;
    const double v = 0.2; /* closing speed */
    double m = sphere_mass(RHO, R), m_eff = m / 2, r_eff = R / 2, es = e_star_same(E, NU);
    double tc = 2.94328 * hertz_max_overlap(m_eff, v, es, r_eff) / v, dt = tc / 4000;
    dem_material mat;
    dem_domain *d = make_domain(0.01, dt, E, 1.0, 0.0, &mat);
    assert_non_null(d);
    add_head_on_pair(d, mat, 0.005, R, 2e-7, v);
    check(run_impact(d, 0, dt), m_eff, v, es, r_eff);
    dem_domain_destroy(d);
}

static void test_sphere_wall(void **state)
{
    (void)state;
    const double v = 0.2;
    double m = sphere_mass(RHO, R), es = e_star_same(E, NU);
    double tc = 2.94328 * hertz_max_overlap(m, v, es, R) / v, dt = tc / 4000;
    dem_material mat;
    dem_domain *d = make_domain(0.01, dt, E, 1.0, 0.0, &mat);
    assert_non_null(d);
    add_sphere_over_floor(d, mat, 0.005, R, 1e-7, v);
    check(run_impact(d, 1, dt), m, v, es, R);
    dem_domain_destroy(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere_sphere),
        cmocka_unit_test(test_sphere_wall),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
