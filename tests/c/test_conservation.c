/* Conservation laws in a closed periodic box (no walls, no gravity):
 *  - energy: e = 1, mu = 0, many collisions; kinetic + Hertz elastic energy must not drift
 *    (relative drift < 1e-6 at dt = t_c/400, the bound; velocity Verlet is
 *    symplectic and the Hertz force is C1 at first touch, so the error stays O(dt^2));
 *  - momentum: with damping and friction on, the total momentum is conserved to round-off
 *    (every pair force is applied as +F / -F): |dp| < 1e-12 of sum |m v|. */
#include "test_util.h"

static const double R = 1e-3, E = 1e7, L = 0.015;

static uint64_t rng = 88172645463325252ULL;
static double urand(void) { return test_urand(&rng); }

static dem_domain *make_gas(double e, double mu, double dt, int n_side)
{
    dem_domain_def def = dem_default_domain_def();
    for (int a = 0; a < 3; a++) {
        def.lo[a] = 0;
        def.hi[a] = L;
        def.periodic[a] = 1;
        def.gravity[a] = 0;
    }
    def.dt = dt;
    dem_domain *d;
    char msg[256];
    assert_int_equal(dem_domain_create(&def, &d, msg, sizeof msg), DEM_OK);
    dem_material mat;
    dem_material_def m = dem_default_material_def();
    m.youngs_modulus = E;
    assert_ok(dem_material_create(d, &m, &mat));
    dem_pair_def p = dem_default_pair_def();
    p.restitution = e;
    p.friction = mu;
    p.rolling_friction = mu > 0 ? 0.1 : 0.0;
    assert_ok(dem_pair_set(d, mat, mat, &p));
    int n = n_side * n_side * n_side;
    double pos[3 * 216], vel[3 * 216], rad[216], mean[3] = {0, 0, 0};
    dem_material mats[216];
    double h = L / n_side;
    for (int k = 0; k < n; k++) {
        int ix = k % n_side, iy = (k / n_side) % n_side, iz = k / (n_side * n_side);
        double c[3] = {ix, iy, iz};
        for (int a = 0; a < 3; a++) {
            pos[3 * k + a] = (c[a] + 0.5) * h + 0.1 * R * (urand() - 0.5);
            vel[3 * k + a] = 0.2 * (urand() - 0.5);
            mean[a] += vel[3 * k + a] / n;
        }
        rad[k] = R * (0.8 + 0.2 * urand());
        mats[k] = mat;
    }
    for (int k = 0; k < n; k++)
        for (int a = 0; a < 3; a++) vel[3 * k + a] -= mean[a];
    assert_ok(dem_particles_add(d, n, pos, rad, mats, vel, vel, NULL));
    return d;
}

static void test_energy(void **st)
{
    (void)st;
    double m = sphere_mass(2500, 0.8 * R);
    double tc = 2.94328 * hertz_max_overlap(m / 2, 0.2, e_star_same(E, 0.25), 0.4 * R) / 0.2;
    dem_domain *d = make_gas(1.0, 0.0, tc / 400, 6);
    dem_diagnostics g0, g;
    assert_ok(dem_domain_diagnostics(d, &g0));
    double e0 = g0.kinetic_energy + g0.elastic_energy, worst = 0;
    int64_t collisions = 0, prev = 0;
    for (int k = 0; k < 200; k++) {
        assert_ok(dem_domain_step(d, 200));
        assert_ok(dem_domain_diagnostics(d, &g));
        worst = fmax(worst, fabs(g.kinetic_energy + g.elastic_energy - e0) / e0);
        if (g.contact_count > prev) collisions += g.contact_count - prev;
        prev = g.contact_count;
    }
    assert_true(collisions > 100); /* the test really exercises contacts */
    assert_close(worst, 0.0, 0, 1e-6);
    dem_domain_destroy(d);
}

static void test_momentum(void **st)
{
    (void)st;
    dem_domain *d = make_gas(0.5, 0.5, 2e-6, 6);
    dem_diagnostics g0, g;
    assert_ok(dem_domain_diagnostics(d, &g0));
    double vel[3 * 216];
    assert_ok(dem_particles_get_velocities(d, vel, dem_particle_count(d)));
    double scale = 0;
    for (int k = 0; k < 3 * 216; k++) scale += sphere_mass(2500, R) * fabs(vel[k]);
    assert_ok(dem_domain_step(d, 20000));
    assert_ok(dem_domain_diagnostics(d, &g));
    assert_true(g.kinetic_energy < 0.9 * g0.kinetic_energy); /* collisions did dissipate */
    for (int a = 0; a < 3; a++) assert_close(g.momentum[a], g0.momentum[a], 0, 1e-12 * scale);
    dem_domain_destroy(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_energy),
        cmocka_unit_test(test_momentum),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
