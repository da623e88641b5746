/* A warm step allocates nothing: after the first steps have sized every buffer (lists,
 * batches, scratch), stepping a settling bed of spheres in an STL box — particle pairs, plane
 * and mesh walls, neighbour-list rebuilds included — makes no malloc, calloc or realloc call
 * from libdem. The test binary is linked with --wrap for those three, so every call from the
 * static library is counted (the OpenMP runtime's own are not libdem's). Why it matters: an
 * engine embedded in another code's time loop must not fragment its heap or take its locks. */
#include "test_util.h"

static long calls;
static int armed; /* DEM_ALLOC_TRAP=1 under gdb stops at the first warm allocation: its backtrace names it */
void *__real_malloc(size_t n);
void *__real_calloc(size_t n, size_t s);
void *__real_realloc(void *p, size_t n);
void *__wrap_malloc(size_t n) { calls++; if (armed && getenv("DEM_ALLOC_TRAP")) __builtin_trap(); return __real_malloc(n); }
void *__wrap_calloc(size_t n, size_t s) { calls++; return __real_calloc(n, s); }
void *__wrap_realloc(void *p, size_t n) { calls++; if (armed && getenv("DEM_ALLOC_TRAP")) __builtin_trap(); return __real_realloc(p, n); }

static void test_warm_steps_do_not_allocate(void **st)
{
    (void)st;
    dem_domain_def def = dem_default_domain_def();
    for (int a = 0; a < 3; a++) {
        def.lo[a] = -0.005;
        def.hi[a] = 0.045;
    }
    def.hi[2] = 0.065;
    def.num_threads = 2;
    dem_domain *d;
    assert_int_equal(dem_domain_create(&def, &d, NULL, 0), DEM_OK);
    dem_material_def m = dem_default_material_def();
    dem_material mat;
    dem_mesh_wall mesh;
    dem_plane_wall wall;
    assert_ok(dem_material_create(d, &m, &mat));
    dem_pair_def p = dem_default_pair_def();
    p.rolling_friction = 0.1;
    assert_ok(dem_pair_set(d, mat, mat, &p));
    dem_mesh_def md = dem_default_mesh_def();
    md.scale = 1e-3;
    md.material = mat;
    assert_ok(dem_mesh_wall_add_stl(d, "data/geometry/open_box_40mm.stl", &md, &mesh));
    dem_plane_wall_def pw = dem_default_plane_wall_def();
    pw.material = mat;
    pw.position = 0.0005; /* a plane just above the box's floor */
    assert_ok(dem_plane_wall_add(d, &pw, &wall));
    enum { NS = 8, NZ = 6 };
    double pos[3 * NS * NS * NZ], rad[NS * NS * NZ];
    dem_material mats[NS * NS * NZ];
    int n = 0;
    for (int k = 0; k < NZ; k++)
        for (int j = 0; j < NS; j++)
            for (int i = 0; i < NS; i++, n++) {
                pos[3 * n] = 0.004 + 0.0045 * i + 0.0004 * (k % 2);
                pos[3 * n + 1] = 0.004 + 0.0045 * j;
                pos[3 * n + 2] = 0.004 + 0.0045 * k;
                rad[n] = 0.002 * (1.0 + 0.05 * ((i * 7 + j * 3 + k) % 5 - 2) / 2.0);
                mats[n] = mat;
            }
    assert_ok(dem_particles_add(d, n, pos, rad, mats, NULL, NULL, NULL));
    /* the team set by hand here (the thread governor's choices depend on the machine's timing) */
    assert_ok(dem_domain_set_adaptive_threads(d, 0));
    /* warm-up: the spheres fall, touch, the lists grow; a few steps on 2 threads, then on one, as
     * the governor may choose after its first probe (20 ms): the second thread's buffer was
     * sized for the loose bed's list */
    assert_ok(dem_domain_step(d, 100));
    assert_ok(dem_domain_set_num_threads(d, 1));
    assert_ok(dem_domain_step(d, 2900));
    /* still settling (contacts come and go, lists rebuild), on 2 threads, then 1, then 2: a
     * change of team must not allocate either (one thread scans every row of a list build) */
    const int team[3] = {2, 1, 2};
    const int steps[3] = {1000, 1000, 1000};
    calls = 0;
    for (int k = 0; k < 3; k++) {
        assert_ok(dem_domain_set_num_threads(d, team[k]));
        armed = 1;
        assert_ok(dem_domain_step(d, steps[k]));
        armed = 0;
    }
    long warm = calls;
    dem_profile prof;
    assert_ok(dem_domain_profile(d, &prof));
    printf("  %ld allocation call(s) in 3000 warm steps on 2, 1, 2 threads (%lld neighbour builds in all 6000)\n",
           warm, (long long)prof.neighbor_builds);
    assert_int_equal(warm, 0);
    dem_domain_destroy(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_warm_steps_do_not_allocate)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
