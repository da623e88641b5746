/* The effect registry and its first member, SJKR cohesion: F = -k_c A added to the Hertz
 * normal force, A = pi a^2 the lens circle of two spheres, pi (R^2 - r^2) against a wall.
 * Static configurations, so the expected force is plain arithmetic: tolerance 1e-12. */
#include "test_util.h"

static const double R = 1e-3, E = 1e7, NU = 0.25, KC = 5e4;

static void test_registry(void **st)
{
    (void)st;
    assert_true(dem_effect_count() >= 1);
    int found = 0;
    for (int i = 0; i < dem_effect_count(); i++) {
        const char *name, *summary, *pname, *unit;
        int np;
        double neutral;
        assert_ok(dem_effect_info(i, &name, &summary, &np));
        for (int p = 0; p < np; p++) assert_ok(dem_effect_param_info(i, p, &pname, &unit, &neutral));
        if (strcmp(name, "cohesion_sjkr") == 0) {
            found = 1;
            assert_int_equal(np, 1);
            assert_ok(dem_effect_param_info(i, 0, &pname, &unit, &neutral));
            assert_string_equal(unit, "J/m^3");
            assert_true(neutral == 0.0);
        }
    }
    assert_true(found);
    assert_int_equal(dem_effect_info(dem_effect_count(), NULL, NULL, NULL), DEM_ERR_UNKNOWN_EFFECT);
}

static double pair_force_z(double kc, double delta)
{
    int mat;
    dem_domain_def def = dem_default_domain_def();
    def.gravity[2] = 0;
    def.insert_overlap_ratio = 0.5; /* allow the deliberate overlap at insertion */
    dem_domain *d;
    assert_int_equal(dem_domain_create(&def, &d, NULL, 0), DEM_OK);
    dem_material_def m = dem_default_material_def();
    m.youngs_modulus = E;
    assert_ok(dem_material_create(d, &m, &mat));
    if (kc > 0) assert_ok(dem_pair_set_effect(d, mat, mat, "cohesion_sjkr", &kc, 1));
    double pos[6] = {0.005, 0.005, 0.005, 0.005, 0.005, 0.005 + 2 * R - delta}, rad[2] = {R, R}, f[6];
    int mats[2] = {mat, mat};
    assert_ok(dem_particles_add(d, 2, pos, rad, mats, NULL, NULL, NULL));
    assert_ok(dem_domain_step(d, 0)); /* forces of the current state */
    assert_ok(dem_particles_get_forces(d, f));
    assert_close(f[5], -f[2], 1e-14, 0); /* action = reaction */
    dem_domain_destroy(d);
    return f[5]; /* on the upper sphere, +z = repulsive */
}

static void test_sjkr_pair(void **st)
{
    (void)st;
    const double delta = 2e-5, es = e_star_same(E, NU), reff = R / 2;
    double hertz = 4.0 / 3.0 * es * sqrt(reff * delta) * delta;
    double dist = 2 * R - delta, s = dist / 2, a2 = R * R - s * s;
    assert_close(pair_force_z(0.0, delta), hertz, 1e-12, 0);
    assert_close(pair_force_z(KC, delta), hertz - KC * M_PI * a2, 1e-12, 0);
}

static void test_sjkr_wall_and_switch_off(void **st)
{
    (void)st;
    int mat, wall;
    dem_domain_def def = dem_default_domain_def();
    def.gravity[2] = 0;
    def.insert_overlap_ratio = 0.5;
    dem_domain *d;
    assert_int_equal(dem_domain_create(&def, &d, NULL, 0), DEM_OK);
    dem_material_def m = dem_default_material_def();
    m.youngs_modulus = E;
    assert_ok(dem_material_create(d, &m, &mat));
    double kc = KC;
    assert_ok(dem_pair_set_effect(d, mat, mat, "cohesion_sjkr", &kc, 1));
    dem_plane_wall_def w = dem_default_plane_wall_def();
    assert_ok(dem_plane_wall_add(d, &w, &wall));
    const double delta = 2e-5, es = e_star_same(E, NU);
    double pos[3] = {0.05, 0.05, R - delta}, rad[1] = {R}, f[3], fw[3];
    assert_ok(dem_particles_add(d, 1, pos, rad, &mat, NULL, NULL, NULL));
    assert_ok(dem_domain_step(d, 0));
    assert_ok(dem_particles_get_forces(d, f));
    double hertz = 4.0 / 3.0 * es * sqrt(R * delta) * delta, r = R - delta;
    assert_close(f[2], hertz - KC * M_PI * (R * R - r * r), 1e-12, 0);
    assert_ok(dem_plane_wall_force(d, wall, fw));
    assert_close(fw[2], -f[2], 1e-14, 0);
    /* neutral value switches the effect off */
    kc = 0.0;
    assert_ok(dem_pair_set_effect(d, mat, mat, "cohesion_sjkr", &kc, 1));
    assert_ok(dem_domain_step(d, 0));
    assert_ok(dem_particles_get_forces(d, f));
    assert_close(f[2], hertz, 1e-12, 0);
    /* bad input */
    kc = -1;
    assert_int_equal(dem_pair_set_effect(d, mat, mat, "cohesion_sjkr", &kc, 1), DEM_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(dem_domain_last_error(d), "cohesion_energy_density"));
    assert_int_equal(dem_pair_set_effect(d, mat, mat, "no_such_effect", &kc, 1), DEM_ERR_UNKNOWN_EFFECT);
    assert_int_equal(dem_pair_set_effect(d, mat, mat, "cohesion_sjkr", &kc, 2), DEM_ERR_INVALID_ARGUMENT);
    dem_domain_destroy(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_registry),
        cmocka_unit_test(test_sjkr_pair),
        cmocka_unit_test(test_sjkr_wall_and_switch_off),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
