/* A host's allocator: with dem_set_allocator every block libdem takes for a domain's life —
 * particles, materials, walls, neighbour lists, an MLP — comes from it and goes back to it
 * (counted blocks: as many frees as allocations once the objects are gone, and the blocks
 * live in between); the allocator cannot change while a domain or an MLP holds memory. */
#include "test_util.h"

static long allocs, frees;

static void *count_malloc(size_t n) { allocs++; return malloc(n); }
static void *count_calloc(size_t c, size_t s) { allocs++; return calloc(c, s); }
static void *count_realloc(void *p, size_t n)
{
    if (!p) allocs++;
    return realloc(p, n);
}
static void count_free(void *p)
{
    if (p) frees++;
    free(p);
}

static void test_every_block_comes_from_the_host_and_goes_back(void **st)
{
    (void)st;
    const dem_allocator mine = {count_malloc, count_calloc, count_realloc, count_free};
    assert_int_equal(dem_set_allocator(&mine), DEM_OK);
    dem_domain_def def = dem_default_domain_def();
    for (int a = 0; a < 3; a++) def.hi[a] = 0.01;
    dem_domain *d;
    assert_int_equal(dem_domain_create(&def, &d, NULL, 0), DEM_OK);
    assert_int_equal(dem_set_allocator(NULL), DEM_ERR_INVALID_ARGUMENT); /* a domain holds memory */
    dem_material_def m = dem_default_material_def();
    dem_material mat;
    dem_plane_wall wall;
    assert_int_equal(dem_material_create(d, &m, &mat), DEM_OK);
    dem_plane_wall_def w = dem_default_plane_wall_def();
    assert_int_equal(dem_plane_wall_add(d, &w, &wall), DEM_OK);
    double x[3 * 27], r[27];
    dem_material mats[27];
    for (int i = 0; i < 27; i++) {
        x[3 * i] = 0.002 + 0.003 * (i % 3);
        x[3 * i + 1] = 0.002 + 0.003 * (i / 3 % 3);
        x[3 * i + 2] = 0.002 + 0.003 * (i / 9);
        r[i] = 0.001;
        mats[i] = mat;
    }
    assert_int_equal(dem_particles_add(d, 27, x, r, mats, NULL, NULL, NULL), DEM_OK);
    assert_int_equal(dem_domain_step(d, 2000), DEM_OK);
    dem_mlp *net;
    char err[128];
    assert_int_equal(dem_mlp_parse("dem-mlp 1\nname q\nunit -\ninputs 1 a\nhidden 1\ninput_lo 0\ninput_hi 1\noutput_lo 0\n"
                                   "output_hi 1\n"
                                   "w1 1\nb1 0\nw2 1\nb2 0\n", &net, err, sizeof err), DEM_OK);
    assert_true(allocs > 20 && frees < allocs); /* the domain's and the net's arrays are live */
    dem_domain_destroy(d);
    assert_int_equal(dem_set_allocator(NULL), DEM_ERR_INVALID_ARGUMENT); /* the net still holds memory */
    dem_mlp_free(net);
    assert_int_equal(frees, allocs); /* every block back to the allocator it came from */
    assert_int_equal(dem_set_allocator(NULL), DEM_OK);
    const dem_allocator partial = {count_malloc, NULL, count_realloc, count_free};
    assert_int_equal(dem_set_allocator(&partial), DEM_ERR_NULL);
    long before = allocs;
    assert_int_equal(dem_domain_create(&def, &d, NULL, 0), DEM_OK); /* the C library's again */
    dem_domain_destroy(d);
    assert_int_equal(allocs, before);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_every_block_comes_from_the_host_and_goes_back)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
