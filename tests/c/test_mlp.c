/* MLP inference and screening (include/dem/mlp.h) against a golden vector: a net exported by
 * scripts/make_mlp_fixture.py and its torch float64 outputs on 64 inputs (hex floats, exact).
 * Tolerance 1e-12 relative (DESIGN section 7): the sums run in another order than torch's
 * matmul and tanh differs by an ulp or two, so agreement is ~1e-15, far inside 1e-12. */
#include "test_util.h"

#include <dem/mlp.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GOLDEN "tests/data/mlp/golden.mlp"
#define GOLDEN_IO "tests/data/mlp/golden_io.txt"
#define NROWS 64

static int read_golden(double x[NROWS][3], double y[NROWS])
{
    FILE *fp = fopen(GOLDEN_IO, "r");
    char line[512];
    int n = 0;
    if (!fp)
        return 0;
    while (fgets(line, sizeof line, fp) && n < NROWS) {
        if (line[0] == '#')
            continue;
        if (sscanf(line, "%la %la %la %la", &x[n][0], &x[n][1], &x[n][2], &y[n]) == 4)
            ++n;
    }
    fclose(fp);
    return n;
}

static void test_golden_outputs(void **state)
{
    double x[NROWS][3], y[NROWS], many[NROWS];
    dem_mlp *net = NULL;
    char err[256] = "";
    int i;
    (void)state;
    assert_int_equal(read_golden(x, y), NROWS);
    assert_int_equal(dem_mlp_load(GOLDEN, &net, err, sizeof err), DEM_OK);
    assert_string_equal(dem_mlp_name(net), "golden");
    assert_string_equal(dem_mlp_unit(net), "");
    assert_int_equal(dem_mlp_num_inputs(net), 3);
    assert_int_equal(dem_mlp_num_hidden(net), 9);
    assert_string_equal(dem_mlp_input_name(net, 1), "rolling_friction");
    assert_null(dem_mlp_input_name(net, 3));
    assert_int_equal(dem_mlp_eval_many(net, &x[0][0], NROWS, many, 2), DEM_OK);
    for (i = 0; i < NROWS; ++i) {
        assert_close(dem_mlp_eval(net, x[i]), y[i], 1e-12, 0.0);
        assert_close(many[i], y[i], 1e-12, 0.0);
    }
    dem_mlp_free(net);
}

static void test_save_round_trip_is_exact(void **state)
{
    dem_mlp *a = NULL, *b = NULL;
    double x[NROWS][3], y[NROWS];
    char err[256];
    int i;
    (void)state;
    read_golden(x, y);
    assert_int_equal(dem_mlp_load(GOLDEN, &a, err, sizeof err), DEM_OK);
    assert_int_equal(dem_mlp_save(a, "build/test_mlp_roundtrip.mlp", err, sizeof err), DEM_OK);
    assert_int_equal(dem_mlp_load("build/test_mlp_roundtrip.mlp", &b, err, sizeof err), DEM_OK);
    for (i = 0; i < NROWS; ++i) /* same weights bit for bit -> same outputs bit for bit */
        assert_true(dem_mlp_eval(a, x[i]) == dem_mlp_eval(b, x[i]));
    dem_mlp_free(a);
    dem_mlp_free(b);
}

static char *golden_text(void)
{
    FILE *fp = fopen(GOLDEN, "rb");
    char *text = calloc(1, 1 << 16);
    size_t n = fread(text, 1, (1 << 16) - 1, fp);
    fclose(fp);
    text[n] = '\0';
    return text;
}

/* Replaces the first line starting with `key` by `line` (NULL: drops it). */
static char *edit(const char *text, const char *key, const char *line)
{
    char *out = calloc(1, strlen(text) + 512);
    const char *p = text;
    while (*p) {
        size_t len = strcspn(p, "\n");
        if (strncmp(p, key, strlen(key)) == 0 && p[strlen(key)] == ' ') {
            if (line) {
                strcat(out, line);
                strcat(out, "\n");
            }
        } else {
            strncat(out, p, len + 1);
        }
        p += len + (p[len] == '\n');
    }
    return out;
}

static void expect_format_error(const char *text, const char *needle)
{
    dem_mlp *net = (dem_mlp *)1;
    char err[256] = "";
    assert_int_equal(dem_mlp_parse(text, &net, err, sizeof err), DEM_ERR_FORMAT);
    assert_null(net);
    if (!strstr(err, needle))
        fail_msg("error '%s' does not mention '%s'", err, needle);
}

static void test_malformed_files_are_named(void **state)
{
    /* each case replaces (or, with NULL, drops) one keyword line of the golden file */
    static const struct { const char *key, *line, *needle; } cases[] = {
        {"b2", NULL, "'b2' is missing"},
        {"b1", "b1 1 2 3", "(b1): expected 9 numbers, found 3"},
        {"w2", "w2 1 2 3 4 5 6 7 8 nan", "(w2): value 9 is not finite"},
        {"hidden", "hidden 0", "(hidden)"},
        {"dem-mlp", "dem-mlp 2", "version 2"},
        {"input_hi", "input_hi 1 0.6 0.2", "restitution"},
        {"b2", "b2 1 2", "more than"},
        {"unit", "colour blue", "line 3: unknown keyword 'colour'"},
        {"b2", "output_transform sqrt", "(output_transform): 'identity' or 'log', not 'sqrt'"},
    };
    char *g = golden_text();
    dem_mlp *net = NULL;
    char err[256] = "";
    size_t k;
    (void)state;
    for (k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        char *t = edit(g, cases[k].key, cases[k].line);
        expect_format_error(t, cases[k].needle);
        free(t);
    }
    assert_int_equal(dem_mlp_load("tests/data/mlp/no_such_file.mlp", &net, err, sizeof err), DEM_ERR_IO);
    assert_non_null(strstr(err, "no_such_file.mlp"));
    assert_int_equal(dem_mlp_parse(NULL, &net, err, sizeof err), DEM_ERR_NULL);
    free(g);
}

/* "output_transform log": the net's output is exp of what the golden net gives (exact: the
 * same sums, then one exp), in eval, eval_many and after a save round trip; "identity" is the
 * golden net itself. */
static void test_log_output_transform(void **state)
{
    double x[NROWS][3], y[NROWS], many[NROWS];
    char *g = golden_text(), err[256] = "";
    char *text = calloc(1, strlen(g) + 64), *ident = calloc(1, strlen(g) + 64);
    dem_mlp *net = NULL, *back = NULL, *same = NULL;
    int i;
    (void)state;
    read_golden(x, y);
    strcpy(text, g);
    strcat(text, "output_transform log\n");
    strcpy(ident, g);
    strcat(ident, "output_transform identity\n");
    assert_int_equal(dem_mlp_parse(text, &net, err, sizeof err), DEM_OK);
    assert_int_equal(dem_mlp_parse(ident, &same, err, sizeof err), DEM_OK);
    assert_int_equal(dem_mlp_eval_many(net, &x[0][0], NROWS, many, 2), DEM_OK);
    assert_int_equal(dem_mlp_save(net, "build/test_mlp_log.mlp", err, sizeof err), DEM_OK);
    assert_int_equal(dem_mlp_load("build/test_mlp_log.mlp", &back, err, sizeof err), DEM_OK);
    for (i = 0; i < NROWS; ++i) {
        const double want = exp(dem_mlp_eval(same, x[i]));
        assert_close(dem_mlp_eval(same, x[i]), y[i], 1e-12, 0.0);
        assert_true(dem_mlp_eval(net, x[i]) == want);
        assert_true(dem_mlp_eval(back, x[i]) == want);
        assert_close(many[i], want, 1e-12, 0.0); /* the screening's tanh differs by an ulp or two */
    }
    dem_mlp_free(net);
    dem_mlp_free(back);
    dem_mlp_free(same);
    free(text);
    free(ident);
    free(g);
}

static void test_screen_keeps_rows_within_the_window(void **state)
{
    double x[NROWS][3], y[NROWS], pred[NROWS * 2], target[2], window[2] = {0.05, 1.0};
    unsigned char keep[NROWS];
    const dem_mlp *nets[2];
    dem_mlp *a = NULL;
    size_t kept = 0, expect = 0;
    char err[256];
    int i;
    (void)state;
    read_golden(x, y);
    assert_int_equal(dem_mlp_load(GOLDEN, &a, err, sizeof err), DEM_OK);
    nets[0] = nets[1] = a;
    target[0] = target[1] = y[7]; /* a window around one golden output */
    assert_int_equal(dem_mlp_screen(nets, 2, target, window, &x[0][0], NROWS, 2, keep, pred, &kept, err, sizeof err),
                     DEM_OK);
    for (i = 0; i < NROWS; ++i) {
        int inside = fabs(y[i] - target[0]) <= 0.05 * fabs(target[0]);
        assert_int_equal(keep[i], inside);
        assert_close(pred[2 * i], y[i], 1e-12, 0.0);
        expect += (size_t)inside;
    }
    assert_true(kept == expect && kept >= 1);
    window[1] = -1.0;
    assert_int_equal(dem_mlp_screen(nets, 2, target, window, &x[0][0], NROWS, 1, keep, NULL, &kept, err, sizeof err),
                     DEM_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(err, "window"));
    dem_mlp_free(a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_golden_outputs),
        cmocka_unit_test(test_save_round_trip_is_exact),
        cmocka_unit_test(test_malformed_files_are_named),
        cmocka_unit_test(test_log_output_transform),
        cmocka_unit_test(test_screen_keeps_rows_within_the_window),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
