/* HDF5 snapshots and PNG rendering.
 *  - restart: a run with mesh walls (servo lid that also turns), plane floor, two particle
 *    materials, rolling friction and cohesion is written mid-way; the run read back and
 *    continued ends bit-for-bit where the uninterrupted run ends (state hash, lid pose, wall
 *    force), including list rebuilds after the restart and a different thread count;
 *  - broken snapshot files get DEM_ERR_IO / DEM_ERR_FORMAT with a message, never a crash;
 *  - rendering: image size, sphere pixels coloured and others not, depth order, colours. */
#include "mesh_util.h"
#include <unistd.h>

static void tmp_path(char *buf, size_t n, const char *name)
{
    snprintf(buf, n, "/tmp/dem_test_%d_%s", (int)getpid(), name);
}

static dem_domain *rich_run(dem_mesh_wall *lid)
{
    dem_domain_def def = dem_default_domain_def();
    for (int a = 0; a < 3; a++) {
        def.lo[a] = -0.001;
        def.hi[a] = a == 2 ? 0.021 : 0.011;
    }
    def.dt = 5e-6;
    dem_domain *d;
    char msg[256];
    assert_ok(dem_domain_create(&def, &d, msg, sizeof msg));
    dem_material_def md = dem_default_material_def();
    dem_material ma;
    dem_material mb;
    dem_material mw;
    assert_ok(dem_material_create(d, &md, &ma));
    md.density = 4000;
    assert_ok(dem_material_create(d, &md, &mb));
    assert_ok(dem_material_create(d, &md, &mw));
    dem_pair_def p = dem_default_pair_def();
    p.rolling_friction = 0.1;
    for (int a = 0; a < 3; a++)
        for (int b = a; b < 3; b++) assert_ok(dem_pair_set(d, (dem_material){a}, (dem_material){b}, &p));
    double coh[1] = {2e3};
    assert_ok(dem_pair_set_effect(d, ma, mb, "cohesion_sjkr", coh, 1));
    dem_plane_wall_def floor = dem_default_plane_wall_def();
    floor.material = mw;
    floor.position = 0.0;
    dem_plane_wall fw;
    assert_ok(dem_plane_wall_add(d, &floor, &fw));
    add_open_box(d, 0.01, 0.02, 2, mw);
    uint64_t rng = 99;
    double pos[3 * 216], rad[216];
    dem_material mats[216];
    for (int k = 0; k < 216; k++) {
        pos[3 * k] = 0.0009 + 0.0016 * (k % 6);
        pos[3 * k + 1] = 0.0009 + 0.0016 * ((k / 6) % 6);
        pos[3 * k + 2] = 0.0009 + 0.0016 * (k / 36);
        rad[k] = 4e-4 + 1e-4 * test_urand(&rng);
        mats[k] = k % 3 == 0 ? mb : ma;
    }
    double vel[3 * 216];
    for (int k = 0; k < 3 * 216; k++) vel[k] = 0.05 * (test_urand(&rng) - 0.5);
    assert_ok(dem_particles_add(d, 216, pos, rad, mats, vel, NULL, NULL));
    assert_ok(dem_domain_set_seed(d, 99));
    assert_ok(dem_domain_step(d, 12000)); /* fallen and nearly settled */
    /* lid just above the bed: servo-loaded and turning about the vertical axis through the
     * box centre */
    double x[3 * 216], r[216], top = 0.0;
    assert_ok(dem_particles_get_positions(d, x, dem_particle_count(d)));
    assert_ok(dem_particles_get_radii(d, r, dem_particle_count(d)));
    for (int k = 0; k < 216; k++) top = fmax(top, x[3 * k + 2] + r[k]);
    *lid = add_grid_mesh(d, 0.0005, 0.0095, 0.0005, 0.0095, top + 2e-4, 3, 3, mw);
    assert_ok(dem_mesh_wall_set_motion(d, *lid, (double[]){0, 0, 0}, (double[]){0, 0, 3.0}, (double[]){0.005, 0.005, top}));
    dem_servo_def sd = dem_default_servo_def();
    sd.target_force = 0.05;
    sd.max_speed = 0.05;
    sd.filter_time = 1e-4;
    assert_ok(dem_mesh_wall_set_servo(d, *lid, &sd));
    assert_ok(dem_domain_step(d, 3000));
    return d;
}

static void finish(dem_domain *d, dem_mesh_wall lid, uint64_t *hash, double pose[12], double force[6])
{
    assert_ok(dem_domain_step(d, 2500));
    assert_ok(dem_domain_step(d, 1500));
    assert_ok(dem_domain_state_hash(d, hash));
    assert_ok(dem_mesh_wall_get_pose(d, lid, pose, pose + 3));
    assert_ok(dem_mesh_wall_force(d, lid, (double[]){0.005, 0.005, 0.0}, force, force + 3));
}

static void test_restart_is_bit_exact(void **state)
{
    (void)state;
    char path[256];
    tmp_path(path, sizeof path, "restart.h5");
    dem_mesh_wall lid;
    dem_domain *a = rich_run(&lid);
    assert_ok(dem_snapshot_write(a, path));
    dem_profile pa0;
    assert_ok(dem_domain_profile(a, &pa0));
    uint64_t ha, hb;
    double pose_a[12], pose_b[12], fa[6], fb[6];
    finish(a, lid, &ha, pose_a, fa);
    dem_profile pa;
    assert_ok(dem_domain_profile(a, &pa));
    assert_true(pa.neighbor_builds > pa0.neighbor_builds); /* the list was rebuilt after the snapshot */

    dem_domain *b = NULL;
    char msg[256];
    assert_ok(dem_snapshot_read(path, &b, msg, sizeof msg));
    assert_int_equal(dem_domain_seed(b), 99);
    assert_int_equal(dem_particle_count(b), 216);
    assert_int_equal(dem_mesh_wall_count(b), 2);
    assert_ok(dem_domain_set_num_threads(b, 2));
    finish(b, lid, &hb, pose_b, fb);
    assert_true(ha == hb);
    assert_memory_equal(pose_a, pose_b, sizeof pose_a);
    assert_memory_equal(fa, fb, sizeof fa);
    double fz = fa[2];
    if (getenv("DEM_TEST_VERBOSE")) printf("  lid force %g N\n", fz);
    assert_true(fz > 0.03 && fz < 0.07); /* the servo holds its 0.05 N (sanity of the scenario) */
    dem_diagnostics da, db;
    assert_ok(dem_domain_diagnostics(a, &da));
    assert_ok(dem_domain_diagnostics(b, &db));
    assert_int_equal(da.step, db.step);
    assert_memory_equal(&da.time, &db.time, sizeof da.time);
    dem_domain_destroy(a);
    dem_domain_destroy(b);
    unlink(path);
}

static void test_broken_snapshots(void **state)
{
    (void)state;
    char path[256], bad[256], msg[256];
    tmp_path(path, sizeof path, "good.h5");
    tmp_path(bad, sizeof bad, "bad.h5");
    dem_material mat;
    dem_domain *d = make_domain(0.01, 1e-6, 5e6, 0.5, 0.5, &mat);
    add_sphere_over_floor(d, mat, 0.005, 1e-3, 1e-4, 0.1);
    assert_ok(dem_domain_step(d, 10));
    assert_ok(dem_snapshot_write(d, path));
    dem_domain *out = (dem_domain *)&mat; /* must be reset to NULL on failure */
    assert_int_equal(dem_snapshot_read("/nonexistent/x.h5", &out, msg, sizeof msg), DEM_ERR_IO);
    assert_null(out);
    assert_non_null(strstr(msg, "cannot open"));
    /* a text file, an empty file, and the good file cut in half */
    FILE *fp = fopen(bad, "wb");
    fputs("hello, I am not HDF5\n", fp);
    fclose(fp);
    assert_int_equal(dem_snapshot_read(bad, &out, msg, sizeof msg), DEM_ERR_FORMAT);
    assert_non_null(strstr(msg, "not an HDF5 file"));
    fp = fopen(bad, "wb");
    fclose(fp);
    assert_int_equal(dem_snapshot_read(bad, &out, msg, sizeof msg), DEM_ERR_FORMAT);
    FILE *in = fopen(path, "rb");
    fseek(in, 0, SEEK_END);
    long len = ftell(in);
    fseek(in, 0, SEEK_SET);
    char *buf = malloc((size_t)len);
    assert_int_equal(fread(buf, 1, (size_t)len, in), (size_t)len);
    fclose(in);
    for (int cut = 1; cut < 8; cut++) { /* truncations at several places */
        fp = fopen(bad, "wb");
        fwrite(buf, 1, (size_t)(len * cut / 8), fp);
        fclose(fp);
        dem_status s = dem_snapshot_read(bad, &out, msg, sizeof msg);
        assert_int_equal(s, DEM_ERR_FORMAT);
        assert_null(out);
        assert_true(strlen(msg) > 0);
    }
    free(buf);
    /* an HDF5 file that is not a snapshot: a write to a directory path fails cleanly, too */
    assert_int_equal(dem_snapshot_write(d, "/nonexistent/dir/x.h5"), DEM_ERR_IO);
    assert_ok(dem_snapshot_read(path, &out, msg, sizeof msg));
    dem_domain_destroy(out);
    dem_domain_destroy(d);
    unlink(path);
    unlink(bad);
}

static const unsigned char *px(const unsigned char *rgb, int w, int x, int y) { return rgb + 3 * (y * w + x); }

static void test_render(void **state)
{
    (void)state;
    dem_material m0;
    dem_material m1;
    dem_domain *d = make_domain(0.01, 1e-6, 5e6, 0.5, 0.5, &m0);
    dem_material_def md = dem_default_material_def();
    assert_ok(dem_material_create(d, &md, &m1));
    /* sphere 0 (material 0) behind sphere 1 (material 1) in the front view (camera at y = -inf) */
    double pos[9] = {0.003, 0.006, 0.005, 0.0035, 0.003, 0.005, 0.008, 0.005, 0.002};
    double rad[3] = {1e-3, 1e-3, 5e-4};
    dem_material mats[3] = {m0, m1, m0};
    assert_ok(dem_particles_add(d, 3, pos, rad, mats, NULL, NULL, NULL));
    dem_render_def rd = dem_default_render_def();
    rd.width = 200;
    rd.height = 100;
    rd.lo[0] = 0.0; /* x from 0 to 10 mm, z from 0 to 5 mm... */
    rd.hi[0] = 0.01;
    rd.lo[1] = 0.0025;
    rd.hi[1] = 0.0075; /* ...2.5 to 7.5 mm: 20 px per mm both ways */
    unsigned char *rgb = malloc(200 * 100 * 3);
    assert_ok(dem_render_rgb(d, &rd, rgb));
    const unsigned char *bg = px(rgb, 200, 5, 5), *c0 = px(rgb, 200, 44, 50), *c1 = px(rgb, 200, 75, 50);
    assert_true(bg[0] == 255 && bg[1] == 255 && bg[2] == 255);
    /* (2.2 mm, 5 mm) is covered only by sphere 0; (3.75 mm, 5 mm) by both: sphere 1 is in front */
    assert_true(c0[2] > c0[0]);  /* palette 0: blue */
    assert_true(c1[0] > c1[2]);  /* palette 1: orange */
    const unsigned char *out = px(rgb, 200, 50 + 21, 50 - 21); /* outside both discs */
    assert_true(out[0] == 255 && out[1] == 255 && out[2] == 255);
    /* sphere 2 at z = 2 mm is below the window: nothing drawn at the bottom right */
    assert_true(px(rgb, 200, 160, 99)[1] == 255);
    /* scalar colours: low value blue, high value red */
    double s[3] = {0.0, 1.0, 0.5};
    rd.color_mode = DEM_COLOR_SCALAR;
    rd.scalar = s;
    assert_ok(dem_render_rgb(d, &rd, rgb));
    c0 = px(rgb, 200, 44, 50);
    c1 = px(rgb, 200, 75, 50);
    assert_true(c0[2] > 100 && c0[0] < 50);
    assert_true(c1[0] > 100 && c1[2] < 50);
    /* PNG: the header says 420 x 230 for the default size */
    char path[256];
    tmp_path(path, sizeof path, "frame.png");
    dem_render_def def = dem_default_render_def();
    def.color_mode = DEM_COLOR_GREY;
    assert_ok(dem_render_png(d, &def, path));
    FILE *fp = fopen(path, "rb");
    unsigned char hdr[24];
    assert_int_equal(fread(hdr, 1, 24, fp), 24);
    fclose(fp);
    assert_memory_equal(hdr + 1, "PNG", 3);
    assert_int_equal((hdr[16] << 24) | (hdr[17] << 16) | (hdr[18] << 8) | hdr[19], 420);
    assert_int_equal((hdr[20] << 24) | (hdr[21] << 16) | (hdr[22] << 8) | hdr[23], 230);
    unlink(path);
    def.width = 0;
    assert_int_equal(dem_render_png(d, &def, path), DEM_ERR_INVALID_ARGUMENT);
    def.width = 10;
    assert_int_equal(dem_render_png(d, &def, "/nonexistent/dir/x.png"), DEM_ERR_IO);
    free(rgb);
    dem_domain_destroy(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_restart_is_bit_exact),
        cmocka_unit_test(test_broken_snapshots),
        cmocka_unit_test(test_render),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
