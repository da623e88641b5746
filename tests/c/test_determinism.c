/* Results are bitwise identical for any thread count (fixed-order force reduction):
 * a settling polydisperse bed with walls, friction and EPSD2 rolling resistance, and a
 * periodic variant, run with 1, 2 and 3 threads, must give the same state hash; so must
 * one long step call and the same steps split into several calls, and a run whose thread
 * count changes between calls (as the thread governor changes it between steps). */
#include "test_util.h"

/* chunks calls of 3000 / chunks steps; call c runs on threads[c % n_threads] threads */
static uint64_t run_bed_varying(const int *threads, int n_threads, int periodic_x, int chunks)
{
    dem_domain_def def = dem_default_domain_def();
    def.lo[0] = def.lo[1] = def.lo[2] = 0;
    def.hi[0] = def.hi[1] = 0.02;
    def.hi[2] = 0.06;
    def.periodic[0] = periodic_x;
    def.num_threads = threads[0];
    def.dt = 1e-5;
    dem_domain *d;
    assert_int_equal(dem_domain_create(&def, &d, NULL, 0), DEM_OK);
    dem_material mat;
    dem_material_def m = dem_default_material_def();
    assert_ok(dem_material_create(d, &m, &mat));
    dem_pair_def p = dem_default_pair_def();
    p.rolling_friction = 0.1;
    assert_ok(dem_pair_set(d, mat, mat, &p));
    const int walls[5][2] = {{0, 1}, {0, -1}, {1, 1}, {1, -1}, {2, 1}};
    for (int k = periodic_x ? 2 : 0; k < 5; k++) {
        dem_plane_wall_def w = dem_default_plane_wall_def();
        w.axis = walls[k][0];
        w.side = walls[k][1];
        w.position = w.side > 0 ? 0.0 : 0.02;
        dem_plane_wall id;
        assert_ok(dem_plane_wall_add(d, &w, &id));
    }
    enum { NX = 9, NZ = 25, N = NX * NX * NZ };
    static double pos[3 * N], vel[3 * N], rad[N];
    static dem_material mats[N];
    uint64_t s = 12345;
    for (int k = 0; k < N; k++) {
        int c[3] = {k % NX, (k / NX) % NX, k / (NX * NX)};
        for (int a = 0; a < 3; a++) {
            s = s * 6364136223846793005ULL + 1442695040888963407ULL;
            pos[3 * k + a] = 1.1e-3 + 2.2e-3 * c[a];
            vel[3 * k + a] = ((double)(s >> 11) / 9007199254740992.0 - 0.5) * 0.1;
        }
        rad[k] = 0.85e-3 + 0.15e-3 * (double)(k % 7) / 6.0;
        mats[k] = mat;
    }
    assert_ok(dem_particles_add(d, N, pos, rad, mats, vel, NULL, NULL));
    uint64_t h0, h;
    assert_ok(dem_domain_state_hash(d, &h0));
    for (int c = 0; c < chunks; c++) {
        assert_ok(dem_domain_set_num_threads(d, threads[c % n_threads]));
        assert_ok(dem_domain_step(d, 3000 / chunks));
    }
    assert_ok(dem_domain_state_hash(d, &h));
    assert_true(h != h0);
    dem_profile prof;
    assert_ok(dem_domain_profile(d, &prof));
    assert_true(prof.neighbor_builds > 1); /* the lists were rebuilt (histories moved) */
    dem_domain_destroy(d);
    return h;
}

static uint64_t run_bed(int threads, int periodic_x, int chunks)
{
    return run_bed_varying(&threads, 1, periodic_x, chunks);
}

static void test_threads_walls(void **st)
{
    (void)st;
    uint64_t h1 = run_bed(1, 0, 1), h2 = run_bed(2, 0, 1), h3 = run_bed(3, 0, 1);
    assert_true(h1 == h2);
    assert_true(h1 == h3);
    assert_true(h1 == run_bed(2, 0, 3)); /* 3 x 1000 steps == 3000 steps */
    const int changing[] = {2, 1, 3, 2, 1, 2};
    assert_true(h1 == run_bed_varying(changing, 6, 0, 12)); /* 2 -> 1 -> 3 -> 2 ... threads */
}

static void test_threads_periodic(void **st)
{
    (void)st;
    uint64_t h1 = run_bed(1, 1, 1), h2 = run_bed(2, 1, 1);
    assert_true(h1 == h2);
    assert_true(h1 != run_bed(1, 0, 1)); /* the hash does see a different run */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_threads_walls),
        cmocka_unit_test(test_threads_periodic),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
