/* Delivered restitution equals the requested one (DESIGN section 3): with the normal force
 * clipped at zero the plain beta(e) damping over-delivers (asked 0.5 -> ~0.55); libdem
 * inverts the clipped impact equation, so the rebound speed / impact speed must equal e
 * for e = 0.1 ... 0.95 at impact speeds spanning 100x (0.05 ... 5 m/s), against a wall and
 * between two spheres. dt = t_c(fastest) / 200, so time discretisation stays well below
 * the 1 % tolerance the issue sets (measured: at most 0.6 %, at e = 0.1, 5 m/s). */
#include "test_util.h"

static const double R = 1e-3, E = 1e9;

/* Rebound speed / impact speed of a sphere on the floor (wall = 1) or of a head-on pair. */
static double rebound(int wall, double e, double v, double dt)
{
    dem_material mat;
    dem_domain *d = make_domain(0.1, dt, E, e, 0.5, &mat);
    if (wall) add_sphere_over_floor(d, mat, 0.05, R, 1e-9, v);
    else add_head_on_pair(d, mat, 0.05, R, 2e-9, v);
    double x[6], u[6];
    for (int s = 0; s < 100000; s++) {
        assert_ok(dem_domain_step(d, 1));
        assert_ok(dem_particles_get_positions(d, x, dem_particle_count(d)));
        if (wall ? x[2] > R : x[5] - x[2] > 2 * R) break; /* contact over */
    }
    assert_ok(dem_particles_get_velocities(d, u, dem_particle_count(d)));
    dem_domain_destroy(d);
    return wall ? u[2] / v : (u[5] - u[2]) / v;
}

static void test_delivered_restitution(void **state)
{
    (void)state;
    const double es[] = {0.1, 0.2, 0.3, 0.5, 0.7, 0.9, 0.95};
    const double vs[] = {0.05, 0.5, 5.0};
    double m = sphere_mass(2500, R), est = e_star_same(E, 0.25);
    double tc_fast = 2.94328 * hertz_max_overlap(m / 2, 5.0, est, R / 2) / 5.0;
    double dt = tc_fast / 200;
    for (size_t i = 0; i < sizeof es / sizeof es[0]; i++)
        for (size_t k = 0; k < sizeof vs / sizeof vs[0]; k++) {
            double ew = rebound(1, es[i], vs[k], dt), ep = rebound(0, es[i], vs[k], dt);
            assert_close(ew, es[i], 0.01, 0);
            assert_close(ep, es[i], 0.01, 0);
        }
}

/* The continuous inversion itself: the plain beta(e) mapping over-delivers with the clip
 * (DESIGN: 0.5 -> ~0.55, 0.3 -> ~0.40), the corrected factor is larger. */
static void test_correction_is_needed(void **state)
{
    (void)state;
    dem_material mat;
    dem_domain *d = make_domain(0.1, 1e-7, E, 0.5, 0.5, &mat);
    double factor;
    assert_ok(dem_pair_damping_factor(d, mat, mat, &factor));
    double beta = log(0.5) / sqrt(log(0.5) * log(0.5) + M_PI * M_PI);
    double plain = -2.0 * sqrt(5.0 / 6.0) * beta;
    assert_true(factor > 1.1 * plain);
    dem_domain_destroy(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_delivered_restitution),
        cmocka_unit_test(test_correction_is_needed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
