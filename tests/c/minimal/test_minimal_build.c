/* libdem built without its optional dependencies (make HDF5=0 PNG=0), linked here without
 * HDF5 or libpng: the engine runs, dem_render_rgb draws, and snapshots and PNG files answer
 * DEM_ERR_UNSUPPORTED with a message saying why (for codes that embed libdem and have no use
 * for them). Run by `make test-minimal` (part of `make test`). */
#include "../test_util.h"

static void test_engine_runs_and_the_left_out_calls_say_so(void **st)
{
    (void)st;
    dem_domain_def def = dem_default_domain_def();
    dem_domain *d;
    assert_int_equal(dem_domain_create(&def, &d, NULL, 0), DEM_OK);
    dem_material_def m = dem_default_material_def();
    dem_material mat;
    dem_plane_wall wall;
    assert_ok(dem_material_create(d, &m, &mat));
    dem_plane_wall_def pw = dem_default_plane_wall_def();
    assert_ok(dem_plane_wall_add(d, &pw, &wall));
    double pos[3] = {0.05, 0.05, 0.002 - 1e-6}, r = 0.002; /* resting on the floor, 1 um into it */
    assert_ok(dem_particles_add(d, 1, pos, &r, &mat, NULL, NULL, NULL));
    assert_ok(dem_domain_step(d, 100));
    double f[3];
    assert_ok(dem_plane_wall_force(d, wall, f));
    assert_true(f[2] < 0.0);
    dem_render_def rd = dem_default_render_def();
    unsigned char *rgb = malloc((size_t)rd.width * rd.height * 3);
    assert_ok(dem_render_rgb(d, &rd, rgb));
    free(rgb);
    assert_int_equal(dem_snapshot_write(d, "never.h5"), DEM_ERR_UNSUPPORTED);
    assert_non_null(strstr(dem_domain_last_error(d), "without HDF5"));
    assert_int_equal(dem_render_png(d, &rd, "never.png"), DEM_ERR_UNSUPPORTED);
    assert_non_null(strstr(dem_domain_last_error(d), "without libpng"));
    char msg[256];
    dem_domain *back = (dem_domain *)&msg; /* must come back NULL */
    assert_int_equal(dem_snapshot_read("never.h5", &back, msg, sizeof msg), DEM_ERR_UNSUPPORTED);
    assert_null(back);
    assert_non_null(strstr(msg, "without HDF5"));
    assert_string_equal(dem_status_name(DEM_ERR_UNSUPPORTED), "DEM_ERR_UNSUPPORTED");
    dem_domain_destroy(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_engine_runs_and_the_left_out_calls_say_so)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
