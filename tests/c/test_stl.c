/* STL loading: ASCII and binary give the same welded mesh; every malformed input gets a
 * clear status and message and leaves the domain usable; the kept fuzz corpus
 * (tests/data/stl_corpus, scripts/make_stl_corpus.py) and in-memory mutations of the seeds
 * never crash the reader (this program also runs under ASan/UBSan in make test). */
#include "test_util.h"
#include "stl.h"
#include <ctype.h>
#include <dirent.h>
#include <unistd.h>

#define CORPUS "tests/data/stl_corpus"

static dem_domain *domain_with_material(dem_material *mat)
{
    return make_domain(2.0, 1e-5, 5e6, 0.5, 0.5, mat);
}

static dem_status load(dem_domain *d, const char *name, dem_material mat, double scale, dem_mesh_wall *mesh)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", CORPUS, name);
    dem_mesh_def md = dem_default_mesh_def();
    md.material = mat;
    md.scale = scale;
    return dem_mesh_wall_add_stl(d, path, &md, mesh);
}

static void test_ascii_and_binary_cube(void **state)
{
    (void)state;
    dem_mesh_wall m;
    dem_material mat;
    dem_domain *d = domain_with_material(&mat);
    const char *names[3] = {"seed_ascii_cube.stl", "seed_binary_cube.stl", "binary_header_says_solid.stl"};
    for (int k = 0; k < 3; k++) {
        assert_ok(load(d, names[k], mat, 0.5, &m));
        dem_mesh_info info;
        assert_ok(dem_mesh_wall_info(d, m, &info));
        assert_int_equal(info.vertex_count, 8); /* 36 corners welded into the 8 cube vertices */
        assert_int_equal(info.triangle_count, 12);
        assert_int_equal(info.edge_count, 18);
        assert_int_equal(info.boundary_edge_count, 0); /* closed */
        assert_int_equal(info.nonmanifold_edge_count, 0);
        assert_int_equal(info.skipped_degenerate, 0);
        assert_close(info.hi[0] - info.lo[0], 0.5, 0, 1e-15); /* scale applied */
    }
    assert_int_equal(dem_mesh_wall_count(d), 3);
    dem_domain_destroy(d);
}

static void expect_error(dem_domain *d, dem_material mat, const char *name, dem_status want, const char *words)
{
    dem_mesh_wall m = {-7};
    int before = dem_mesh_wall_count(d);
    dem_status s = load(d, name, mat, 1.0, &m);
    if (s != want || !strstr(dem_domain_last_error(d), words)) {
        print_error("%s: got %s '%s', want %s with '%s'\n", name, dem_status_name(s), dem_domain_last_error(d),
                    dem_status_name(want), words);
        fail();
    }
    assert_int_equal(m.index, -7); /* the handle is untouched on failure */
    assert_int_equal(dem_mesh_wall_count(d), before);
}

static void test_malformed_files(void **state)
{
    (void)state;
    dem_material mat;
    dem_domain *d = domain_with_material(&mat);
    expect_error(d, mat, "no_such_file.stl", DEM_ERR_IO, "cannot open");
    expect_error(d, mat, "", DEM_ERR_IO, "cannot read"); /* the corpus directory itself */
    expect_error(d, mat, "empty.stl", DEM_ERR_FORMAT, "empty file");
    expect_error(d, mat, "truncated_binary.stl", DEM_ERR_FORMAT, "truncated or corrupt");
    expect_error(d, mat, "count_too_large.stl", DEM_ERR_FORMAT, "header says 13 triangles");
    expect_error(d, mat, "count_huge.stl", DEM_ERR_FORMAT, "header says 4294967295 triangles");
    expect_error(d, mat, "nan_ascii.stl", DEM_ERR_FORMAT, "non-finite");
    expect_error(d, mat, "inf_ascii.stl", DEM_ERR_FORMAT, "non-finite");
    expect_error(d, mat, "nan_binary.stl", DEM_ERR_FORMAT, "triangle 0 has a non-finite");
    expect_error(d, mat, "missing_endsolid.stl", DEM_ERR_FORMAT, "missing 'endsolid'");
    expect_error(d, mat, "junk_token.stl", DEM_ERR_FORMAT, "expected 'loop'");
    expect_error(d, mat, "short_header.stl", DEM_ERR_FORMAT, "neither ASCII STL nor a binary STL");
    expect_error(d, mat, "all_degenerate.stl", DEM_ERR_FORMAT, "zero area");
    /* the domain is still usable */
    dem_mesh_wall m;
    assert_ok(load(d, "seed_ascii_cube.stl", mat, 1.0, &m));
    assert_int_equal(m.index, 0);
    assert_ok(dem_domain_step(d, 3));
    dem_domain_destroy(d);
}

/* Spreadsheet- and CAD-written ASCII files: a UTF-8 byte-order mark, leading white space and
 * upper-case keywords read as the plain file does (12 triangles of the seed cube). */
static void test_ascii_bom_and_upper_case(void **state)
{
    (void)state;
    FILE *f = fopen(CORPUS "/seed_ascii_cube.stl", "rb");
    assert_non_null(f);
    static char text[1 << 16];
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    static unsigned char buf[(1 << 16) + 8];
    for (int variant = 0; variant < 3; variant++) {
        size_t len = 0;
        if (variant != 1) { /* 0: BOM; 2: BOM + upper case */
            buf[0] = 0xEF, buf[1] = 0xBB, buf[2] = 0xBF;
            len = 3;
        } else {
            buf[0] = '\n', buf[1] = ' ';
            len = 2;
        }
        for (size_t k = 0; k < n; k++) buf[len++] = (unsigned char)(variant >= 1 ? toupper((unsigned char)text[k]) : text[k]);
        stl_soup soup;
        char err[256];
        if (dem_stl_parse(buf, len, &soup, err, sizeof err) != STL_OK) {
            print_error("variant %d: %s\n", variant, err);
            fail();
        }
        assert_int_equal(soup.n, 12);
        free(soup.xyz);
    }
}

static void test_degenerate_triangles_skipped(void **state)
{
    (void)state;
    dem_mesh_wall m;
    dem_material mat;
    dem_domain *d = domain_with_material(&mat);
    /* a square of two triangles plus a sliver (collinear) and a collapsed one */
    double v[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0, 0};
    int32_t t[] = {0, 1, 2, 0, 2, 3, 0, 4, 1, 2, 2, 3};
    dem_mesh_def md = dem_default_mesh_def();
    md.material = mat;
    assert_ok(dem_mesh_wall_add(d, 5, v, 4, t, &md, &m));
    dem_mesh_info info;
    assert_ok(dem_mesh_wall_info(d, m, &info));
    assert_int_equal(info.skipped_degenerate, 2);
    assert_int_equal(info.triangle_count, 2);
    assert_int_equal(info.vertex_count, 4);     /* the unused midpoint is dropped */
    assert_int_equal(info.boundary_edge_count, 4);
    /* bad arrays */
    int32_t bad_t[] = {0, 1, 9};
    assert_int_equal(dem_mesh_wall_add(d, 5, v, 1, bad_t, &md, &m), DEM_ERR_INVALID_ARGUMENT);
    double nan_v[] = {0, 0, 0, 1, 0, NAN, 1, 1, 0};
    assert_int_equal(dem_mesh_wall_add(d, 3, nan_v, 1, t, &md, &m), DEM_ERR_FORMAT);
    md.scale = -1;
    assert_int_equal(dem_mesh_wall_add(d, 5, v, 2, t, &md, &m), DEM_ERR_INVALID_ARGUMENT);
    md.scale = 1;
    md.material = (dem_material){99};
    assert_int_equal(dem_mesh_wall_add(d, 5, v, 2, t, &md, &m), DEM_ERR_UNKNOWN_MATERIAL);
    assert_int_equal(dem_mesh_wall_count(d), 1);
    dem_domain_destroy(d);
}

/* A mesh through an existing particle is refused, and a particle added into a mesh too. */
static void test_mesh_particle_overlap(void **state)
{
    (void)state;
    dem_material mat;
    dem_mesh_wall m;
    dem_domain *d = domain_with_material(&mat);
    double p[3] = {0.5, 0.5, 0.5}, r = 0.01;
    assert_ok(dem_particles_add(d, 1, p, &r, &mat, NULL, NULL, NULL));
    double v[] = {0, 0, 0.505, 1, 0, 0.505, 1, 1, 0.505, 0, 1, 0.505};
    int32_t t[] = {0, 1, 2, 0, 2, 3};
    dem_mesh_def md = dem_default_mesh_def();
    md.material = mat;
    assert_int_equal(dem_mesh_wall_add(d, 4, v, 2, t, &md, &m), DEM_ERR_OVERLAP);
    md.offset[2] = 0.1;
    assert_ok(dem_mesh_wall_add(d, 4, v, 2, t, &md, &m));
    double q[3] = {0.3, 0.3, 0.6};
    assert_int_equal(dem_particles_add(d, 1, q, &r, &mat, NULL, NULL, NULL), DEM_ERR_OVERLAP);
    assert_non_null(strstr(dem_domain_last_error(d), "mesh wall 0"));
    dem_domain_destroy(d);
}

static unsigned char *read_all(const char *path, size_t *len)
{
    FILE *fp = fopen(path, "rb");
    assert_non_null(fp);
    fseek(fp, 0, SEEK_END);
    long n = ftell(fp);
    fseek(fp, 0, SEEK_SET);
    unsigned char *b = malloc((size_t)n + 1);
    *len = fread(b, 1, (size_t)n, fp);
    fclose(fp);
    return b;
}

/* Every corpus file: a clean status (OK or a named error), never a crash. Then 3000
 * in-memory mutations of each seed straight into the parser. */
static void test_fuzz_corpus(void **state)
{
    (void)state;
    dem_material mat;
    dem_mesh_wall m;
    int files = 0, ok = 0;
    dem_domain *d = domain_with_material(&mat);
    DIR *dir = opendir(CORPUS);
    assert_non_null(dir);
    struct dirent *e;
    while ((e = readdir(dir)) != NULL) {
        if (!strstr(e->d_name, ".stl")) continue;
        dem_status s = load(d, e->d_name, mat, 1.0, &m);
        assert_true(s == DEM_OK || s == DEM_ERR_FORMAT);
        assert_true(s == DEM_OK || strlen(dem_domain_last_error(d)) > 0);
        files++;
        ok += s == DEM_OK;
    }
    closedir(dir);
    assert_true(files >= 50);
    assert_true(ok >= 3 && ok < files);
    dem_domain_destroy(d);

    const char *seeds[2] = {CORPUS "/seed_ascii_cube.stl", CORPUS "/seed_binary_cube.stl"};
    uint64_t rng = 12345;
    for (int s = 0; s < 2; s++) {
        size_t len;
        unsigned char *seed = read_all(seeds[s], &len);
        unsigned char *buf = malloc(len + 64);
        for (int it = 0; it < 3000; it++) {
            memcpy(buf, seed, len);
            size_t n = len;
            int flips = 1 + (int)(test_urand(&rng) * 6);
            for (int k = 0; k < flips; k++) buf[(size_t)(test_urand(&rng) * (double)n)] ^= (unsigned char)(1u << (int)(test_urand(&rng) * 8));
            if (test_urand(&rng) < 0.3) n = (size_t)(test_urand(&rng) * (double)n);
            stl_soup soup;
            char err[256];
            int rc = dem_stl_parse(buf, n, &soup, err, sizeof err);
            assert_true(rc == STL_OK || rc == STL_BAD);
            if (rc == STL_OK) {
                for (int64_t k = 0; k < 9 * soup.n; k++) assert_true(isfinite(soup.xyz[k]));
                free(soup.xyz);
            } else {
                assert_null(soup.xyz);
                assert_true(strlen(err) > 0);
            }
        }
        free(buf);
        free(seed);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ascii_and_binary_cube),
        cmocka_unit_test(test_malformed_files),
        cmocka_unit_test(test_ascii_bom_and_upper_case),
        cmocka_unit_test(test_degenerate_triangles_skipped),
        cmocka_unit_test(test_mesh_particle_overlap),
        cmocka_unit_test(test_fuzz_corpus),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
