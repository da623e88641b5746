/* API misuse returns the right status with a message naming the problem and leaves the
 * domain usable; broken runs (unstable dt, runaway overlap, NaN, escape) stop with a
 * status naming the particle. */
#include "test_util.h"

#define assert_status(call, expected)                                                                           \
    do {                                                                                                        \
        dem_status s_ = (call);                                                                                 \
        if (s_ != (expected)) {                                                                                 \
            print_error("%s returned %s, expected %s\n", #call, dem_status_name(s_), dem_status_name(expected)); \
            fail();                                                                                             \
        }                                                                                                       \
    } while (0)

#define assert_msg(d, needle)                                                                                   \
    do {                                                                                                        \
        if (!strstr(dem_domain_last_error(d), (needle))) {                                                      \
            print_error("message '%s' lacks '%s'\n", dem_domain_last_error(d), (needle));                       \
            fail();                                                                                             \
        }                                                                                                       \
    } while (0)

static void test_version(void **st)
{
    (void)st;
    int a, b, c;
    dem_version(&a, &b, &c);
    assert_int_equal(a, DEM_VERSION_MAJOR);
    assert_int_equal(b, DEM_VERSION_MINOR);
    assert_int_equal(c, DEM_VERSION_PATCH);
    assert_string_equal(dem_version_string(), DEM_VERSION_STRING);
    assert_string_equal(dem_status_name(DEM_ERR_OVERLAP), "DEM_ERR_OVERLAP");
}

static void test_create_errors(void **st)
{
    (void)st;
    char msg[256];
    dem_domain *d = (dem_domain *)1;
    dem_domain_def def = dem_default_domain_def();
    def.dt = NAN;
    assert_status(dem_domain_create(&def, &d, msg, sizeof msg), DEM_ERR_INVALID_ARGUMENT);
    assert_null(d);
    assert_non_null(strstr(msg, "dt"));
    def = dem_default_domain_def();
    def.hi[1] = def.lo[1];
    assert_status(dem_domain_create(&def, &d, msg, sizeof msg), DEM_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(msg, "axis 1"));
    assert_status(dem_domain_create(NULL, &d, msg, sizeof msg), DEM_ERR_NULL);
    assert_status(dem_domain_create(&def, NULL, NULL, 0), DEM_ERR_NULL);
}

static void test_misuse_leaves_domain_usable(void **st)
{
    (void)st;
    dem_material mat;
    dem_domain *d = make_domain(0.01, 1e-6, 1e7, 0.5, 0.5, &mat);
    dem_material_def m = dem_default_material_def();
    dem_material other;
    m.youngs_modulus = 0;
    assert_status(dem_material_create(d, &m, &other), DEM_ERR_INVALID_ARGUMENT);
    assert_msg(d, "Young");
    m.youngs_modulus = -5;
    assert_status(dem_material_create(d, &m, &other), DEM_ERR_INVALID_ARGUMENT);
    m = dem_default_material_def();
    m.poisson_ratio = 0.5;
    assert_status(dem_material_create(d, &m, &other), DEM_ERR_INVALID_ARGUMENT);
    assert_msg(d, "Poisson");
    assert_status(dem_material_create(d, NULL, &other), DEM_ERR_NULL);
    assert_int_equal(dem_material_count(d), 1);

    dem_pair_def p = dem_default_pair_def();
    const double bad_e[] = {0.0, -0.1, 1.01, NAN};
    for (int k = 0; k < 4; k++) {
        p.restitution = bad_e[k];
        assert_status(dem_pair_set(d, mat, mat, &p), DEM_ERR_INVALID_ARGUMENT);
        assert_msg(d, "restitution");
    }
    p = dem_default_pair_def();
    p.friction = -0.1;
    assert_status(dem_pair_set(d, mat, mat, &p), DEM_ERR_INVALID_ARGUMENT);
    assert_msg(d, "sliding friction");
    p = dem_default_pair_def();
    p.rolling_friction = -1;
    assert_status(dem_pair_set(d, mat, mat, &p), DEM_ERR_INVALID_ARGUMENT);
    assert_msg(d, "rolling friction");
    p = dem_default_pair_def();
    assert_status(dem_pair_set(d, mat, (dem_material){7}, &p), DEM_ERR_UNKNOWN_MATERIAL);
    assert_msg(d, "unknown material");
    dem_pair_def got;
    assert_ok(dem_pair_get(d, mat, mat, &got));
    assert_true(got.restitution == 0.5 && got.friction == 0.5); /* unchanged */

    double pos[6] = {0.005, 0.005, 0.005, 0.005, 0.005, 0.0075}, rad[2] = {1e-3, 1e-3};
    dem_material mats[2] = {mat, mat};
    double nan_rad[2] = {1e-3, NAN}, neg_rad[2] = {1e-3, -1e-3};
    assert_status(dem_particles_add(d, 2, pos, nan_rad, mats, NULL, NULL, NULL), DEM_ERR_INVALID_ARGUMENT);
    assert_msg(d, "particle 1: radius");
    assert_status(dem_particles_add(d, 2, pos, neg_rad, mats, NULL, NULL, NULL), DEM_ERR_INVALID_ARGUMENT);
    dem_material bad_mats[2] = {mat, {3}};
    assert_status(dem_particles_add(d, 2, pos, rad, bad_mats, NULL, NULL, NULL), DEM_ERR_UNKNOWN_MATERIAL);
    assert_msg(d, "particle 1: unknown material 3");
    assert_status(dem_particles_add(d, 2, NULL, rad, mats, NULL, NULL, NULL), DEM_ERR_NULL);
    double nan_pos[6] = {0.005, 0.005, NAN, 0.005, 0.005, 0.0075};
    assert_status(dem_particles_add(d, 2, nan_pos, rad, mats, NULL, NULL, NULL), DEM_ERR_INVALID_ARGUMENT);
    double out_pos[6] = {0.005, 0.005, 0.005, 0.005, 0.005, 0.02};
    assert_status(dem_particles_add(d, 2, out_pos, rad, mats, NULL, NULL, NULL), DEM_ERR_OUT_OF_BOUNDS);
    double overlap_pos[6] = {0.005, 0.005, 0.005, 0.005, 0.005, 0.0065};
    assert_status(dem_particles_add(d, 2, overlap_pos, rad, mats, NULL, NULL, NULL), DEM_ERR_OVERLAP);
    assert_msg(d, "particles 0 and 1 overlap");
    assert_int_equal(dem_particle_count(d), 0); /* all-or-nothing */

    dem_particle_id ids[2];
    assert_ok(dem_particles_add(d, 2, pos, rad, mats, NULL, NULL, ids));
    assert_int_equal(dem_particle_count(d), 2);
    assert_string_equal(dem_domain_last_error(d), "");
    double again[3] = {0.005, 0.005, 0.0055};
    assert_status(dem_particles_add(d, 1, again, rad, mats, NULL, NULL, NULL), DEM_ERR_OVERLAP);
    assert_msg(d, "existing particle id 0");
    dem_particle_id ghost = 99;
    assert_status(dem_particles_remove(d, 1, &ghost), DEM_ERR_UNKNOWN_PARTICLE);
    dem_plane_wall_def w = dem_default_plane_wall_def();
    w.axis = 3;
    dem_plane_wall wall;
    assert_status(dem_plane_wall_add(d, &w, &wall), DEM_ERR_INVALID_ARGUMENT);
    w = dem_default_plane_wall_def();
    w.position = 0.0052; /* cuts particle 0 */
    assert_status(dem_plane_wall_add(d, &w, &wall), DEM_ERR_OVERLAP);
    assert_status(dem_domain_step(d, -1), DEM_ERR_INVALID_ARGUMENT);
    assert_status(dem_domain_set_dt(d, -1e-6), DEM_ERR_INVALID_ARGUMENT);
    assert_status(dem_domain_set_num_threads(d, 0), DEM_ERR_INVALID_ARGUMENT);
    assert_status(dem_domain_set_adaptive_threads(d, 2), DEM_ERR_INVALID_ARGUMENT);
    assert_ok(dem_domain_set_adaptive_threads(d, 0));
    assert_ok(dem_domain_set_adaptive_threads(d, 1));
    assert_status(dem_domain_step(NULL, 1), DEM_ERR_NULL);

    /* still usable */
    assert_ok(dem_domain_step(d, 100));
    assert_ok(dem_particles_remove(d, 1, &ids[0]));
    assert_int_equal(dem_particle_count(d), 1);
    dem_particle_id left;
    assert_ok(dem_particles_get_ids(d, &left, dem_particle_count(d)));
    assert_int_equal(left, ids[1]);
    assert_ok(dem_domain_step(d, 100));
    dem_domain_destroy(d);
}

static void test_timestep_checks(void **st)
{
    (void)st;
    dem_material mat;
    dem_domain *d = make_domain(0.01, 1e-6, 1e7, 0.5, 0.5, &mat);
    double pos[3] = {0.005, 0.005, 0.005}, rad[1] = {1e-3};
    assert_ok(dem_particles_add(d, 1, pos, rad, &mat, NULL, NULL, NULL));
    dem_timestep_info ti;
    assert_ok(dem_domain_timestep_info(d, &ti));
    /* Rayleigh time of a 1 mm sphere, E = 1e7, nu = 0.25, rho = 2500 */
    double g = 1e7 / 2.5, tr = M_PI * 1e-3 * sqrt(2500 / g) / (0.1631 * 0.25 + 0.8766);
    assert_close(ti.rayleigh_time, tr, 1e-12, 0);
    assert_true(ti.suggested_dt <= 0.1 * tr && ti.suggested_dt > 0);
    assert_ok(dem_domain_set_dt(d, 0.5 * tr));
    assert_status(dem_domain_step(d, 1), DEM_WARN_TIMESTEP_LARGE);
    assert_msg(d, "Rayleigh");
    assert_ok(dem_domain_set_dt(d, 1.5 * tr));
    assert_status(dem_domain_step(d, 1), DEM_ERR_UNSTABLE_TIMESTEP);
    assert_msg(d, "exceeds the Rayleigh time");
    dem_domain_destroy(d);
}

static void test_broken_runs_name_the_particle(void **st)
{
    (void)st;
    /* escape through a closed face */
    dem_material mat;
    dem_domain *d = make_domain(0.01, 1e-6, 1e7, 0.5, 0.5, &mat);
    double pos[6] = {0.002, 0.005, 0.005, 0.008, 0.005, 0.005}, rad[2] = {1e-3, 1e-3};
    double vel[6] = {0, 0, 0, 0, 0, 50.0};
    dem_material mats[2] = {mat, mat};
    assert_ok(dem_particles_add(d, 2, pos, rad, mats, vel, NULL, NULL));
    assert_status(dem_domain_step(d, 1000), DEM_ERR_OUT_OF_BOUNDS);
    assert_msg(d, "particle id 1 left the domain");
    dem_domain_destroy(d);

    /* runaway overlap: a fast head-on impact at a time step near the Rayleigh time */
    d = make_domain(0.01, 1e-6, 1e6, 0.5, 0.5, &mat);
    double vel2[6] = {30, 0, 0, -30, 0, 0};
    double pos2[6] = {0.004, 0.005, 0.005, 0.006 + 1e-5, 0.005, 0.005};
    assert_ok(dem_particles_add(d, 2, pos2, rad, mats, vel2, NULL, NULL));
    dem_timestep_info ti;
    assert_ok(dem_domain_timestep_info(d, &ti));
    assert_ok(dem_domain_set_dt(d, 0.15 * ti.rayleigh_time));
    assert_status(dem_domain_step(d, 100), DEM_ERR_RUNAWAY_OVERLAP);
    assert_msg(d, "id 0");
    assert_msg(d, "id 1");
    dem_domain_destroy(d);

    /* NaN: an absurd gravity overflows the velocity to inf in a periodic box */
    dem_domain_def def = dem_default_domain_def();
    def.periodic[0] = def.periodic[1] = def.periodic[2] = 1;
    def.gravity[2] = -1e308;
    def.dt = 1e10;
    assert_int_equal(dem_domain_create(&def, &d, NULL, 0), DEM_OK);
    dem_material_def m = dem_default_material_def();
    m.youngs_modulus = 1e-100;
    assert_ok(dem_material_create(d, &m, &mat));
    assert_ok(dem_particles_add(d, 1, pos, rad, &mat, NULL, NULL, NULL));
    assert_status(dem_domain_step(d, 10), DEM_ERR_NUMERICAL);
    assert_msg(d, "particle id 0");
    dem_domain_destroy(d);
}

static void test_lifecycle_edges(void **st)
{
    (void)st;
    dem_material mat;
    dem_domain *d = make_domain(0.01, 1e-6, 1e7, 0.5, 0.5, &mat);
    assert_ok(dem_domain_step(d, 10)); /* no particles: time still advances */
    dem_diagnostics g;
    assert_ok(dem_domain_diagnostics(d, &g));
    assert_int_equal(g.step, 10);
    double pos[6] = {0.003, 0.005, 0.005, 0.007, 0.005, 0.005}, rad[2] = {1e-3, 1e-3}, v[6];
    dem_material mats[2] = {mat, mat};
    dem_particle_id ids[2], more[2];
    assert_ok(dem_particles_add(d, 2, pos, rad, mats, NULL, NULL, ids));
    assert_ok(dem_domain_step(d, 10));
    assert_ok(dem_particles_remove(d, 2, ids)); /* remove everything */
    assert_int_equal(dem_particle_count(d), 0);
    assert_ok(dem_domain_step(d, 10));
    assert_ok(dem_particles_add(d, 2, pos, rad, mats, NULL, NULL, more)); /* ids are never reused */
    assert_true(more[0] == ids[1] + 1 && more[1] == ids[1] + 2);
    assert_status(dem_particles_get_positions(d, NULL, dem_particle_count(d)), DEM_ERR_NULL);
    double bad_v[6] = {0, 0, 0, NAN, 0, 0};
    assert_status(dem_particles_set_velocities(d, bad_v), DEM_ERR_INVALID_ARGUMENT);
    assert_ok(dem_particles_get_velocities(d, v, dem_particle_count(d)));
    for (int k = 0; k < 6; k++) assert_true(v[k] == 0.0); /* unchanged */
    dem_particle_id twice[2] = {more[0], more[0]};
    assert_status(dem_particles_remove(d, 2, twice), DEM_ERR_UNKNOWN_PARTICLE);
    assert_msg(d, "listed twice");
    assert_int_equal(dem_particle_count(d), 2);
    assert_ok(dem_domain_step(d, 10));
    dem_domain_destroy(d);
    dem_domain_destroy(NULL); /* harmless */
}

static void test_periodic_too_small(void **st)
{
    (void)st;
    dem_domain_def def = dem_default_domain_def();
    def.periodic[0] = 1;
    def.hi[0] = 0.005; /* < 3 x (2 R + skin) for R = 1 mm */
    dem_domain *d;
    assert_int_equal(dem_domain_create(&def, &d, NULL, 0), DEM_OK);
    dem_material mat;
    dem_material_def m = dem_default_material_def();
    assert_ok(dem_material_create(d, &m, &mat));
    double pos[3] = {0.0025, 0.05, 0.05}, rad[1] = {1e-3};
    assert_ok(dem_particles_add(d, 1, pos, rad, &mat, NULL, NULL, NULL));
    assert_status(dem_domain_step(d, 1), DEM_ERR_INVALID_ARGUMENT);
    assert_msg(d, "periodic axis 0");
    dem_domain_destroy(d);
}

/* The assert hook receives a broken invariant (the checking build raises them: make test-sanitize). */
void dem_assert_fail(const char *expr, const char *file, int line); /* internal; the static library has it */
static const char *hooked_expr;
static int hooked_line;
static void hook(const char *expr, const char *file, int line)
{
    (void)file;
    hooked_expr = expr;
    hooked_line = line;
}

static void test_assert_hook(void **st)
{
    (void)st;
    dem_set_assert_hook(hook);
    dem_assert_fail("start[i] <= start[i + 1]", "neighbor.c", 42);
    assert_string_equal(hooked_expr, "start[i] <= start[i + 1]");
    assert_int_equal(hooked_line, 42);
    dem_set_assert_hook(NULL);
}

/* Read-back buffers carry their capacity: a short one is refused, untouched, with the counts. */
static void test_getters_check_capacity(void **st)
{
    (void)st;
    dem_domain_def def = dem_default_domain_def();
    dem_domain *d;
    assert_int_equal(dem_domain_create(&def, &d, NULL, 0), DEM_OK);
    dem_material_def m = dem_default_material_def();
    dem_material mat;
    assert_ok(dem_material_create(d, &m, &mat));
    double pos[6] = {0.02, 0.02, 0.02, 0.06, 0.06, 0.06}, rad[2] = {0.005, 0.005}, out[6] = {-1, -1, -1, -1, -1, -1};
    dem_material mats[2] = {mat, mat};
    assert_ok(dem_particles_add(d, 2, pos, rad, mats, NULL, NULL, NULL));
    assert_int_equal(dem_particles_get_positions(d, out, 1), DEM_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(dem_domain_last_error(d), "room for 1 particles, 2 to write"));
    for (int k = 0; k < 6; k++) assert_true(out[k] == -1.0); /* nothing written */
    dem_particle_id ids[2];
    assert_int_equal(dem_particles_get_ids(d, ids, 0), DEM_ERR_INVALID_ARGUMENT);
    assert_ok(dem_particles_get_positions(d, out, 2));
    assert_true(out[3] == 0.06);
    dem_domain_destroy(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_version),
        cmocka_unit_test(test_create_errors),
        cmocka_unit_test(test_misuse_leaves_domain_usable),
        cmocka_unit_test(test_timestep_checks),
        cmocka_unit_test(test_broken_runs_name_the_particle),
        cmocka_unit_test(test_periodic_too_small),
        cmocka_unit_test(test_lifecycle_edges),
        cmocka_unit_test(test_getters_check_capacity),
        cmocka_unit_test(test_assert_hook),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
