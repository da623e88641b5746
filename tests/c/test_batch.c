/* The batched pair law (libdem/pair_batch.c) against the scalar contact law (contact_law.h):
 * random contacts — fresh and loaded springs, sticking and sliding, rolling springs below and
 * at their limit, several pair types in one batch or one type (the uniform loop) — must give
 * bit-identical forces, torques, overlaps and updated histories. Tolerance zero: the batch loop is the same sequence
 * of IEEE operations, and the engine's results (and the published benchmarks) rely on it.
 * Every rolling model (CDT, EPSD with its dashpot, EPSD2), alone in a batch or mixed, must
 * match too, and so must contacts with effects (cohesion, twisting resistance), alone, mixed with
 * dry ones, with and without rolling. The wall form of the loop (mesh contacts) must match
 * wall_contact_in() + contact_law() the same way. */
#include "test_util.h"
#include "contact_law.h"
#include "pair_batch.h"
#include <string.h>

static uint64_t rng_state = 88172645463325252ull;
static double uniform(double lo, double hi)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return lo + (hi - lo) * (double)(rng_state >> 11) / 9007199254740992.0;
}

static pair_props props(double friction, double mu_r, dem_rolling_model model, double e_star)
{
    pair_props p;
    memset(&p, 0, sizeof p);
    p.def.restitution = 0.5;
    p.def.friction = friction;
    p.def.rolling_friction = mu_r;
    p.def.rolling_model = model;
    p.def.rolling_damping = 0.3;
    p.e_star = e_star;
    p.g_star = 0.4 * e_star;
    p.damping_factor = 0.7;
    p.st_over_sn_sqrt = sqrt(4.0 * p.g_star / e_star);
    return p;
}

/* The same with effects switched on (a zero parameter leaves that effect off). */
static pair_props with_effects(pair_props p, double cohesion, double twisting)
{
    if (cohesion > 0.0) {
        p.effects[p.n_effects].effect = dem_effect_find("cohesion_sjkr");
        p.effects[p.n_effects++].params[0] = cohesion;
    }
    if (twisting > 0.0) {
        p.effects[p.n_effects].effect = dem_effect_find("twisting_resistance");
        p.effects[p.n_effects++].params[0] = twisting;
    }
    return p;
}

/* Whether any of the first m contacts (pair type q % n_types) has effects. */
static int any_effects(const pair_props *types, int n_types, int m)
{
    int any = 0;
    for (int q = 0; q < m; q++) any |= types[q % n_types].n_effects > 0;
    return any;
}

/* One random contact into slot q of the batch (and its starting history into h0). */
static void random_contact(pair_batch *b, int q, const pair_props *pp, double *h0)
{
    const double ri = uniform(0.8e-3, 1.2e-3), rj = uniform(0.8e-3, 1.2e-3);
    const double theta = uniform(0, 3.141592653589793), phi = uniform(0, 6.283185307179586), dist = (ri + rj) * (1.0 - uniform(1e-5, 0.02));
    b->k[q] = 6 * q + 1; /* entries of a pretend list: gaps like a real one */
    b->j[q] = q;
    b->pp[q] = pp;
    b->dx[q] = dist * sin(theta) * cos(phi);
    b->dy[q] = dist * sin(theta) * sin(phi);
    b->dz[q] = dist * cos(theta);
    b->r2[q] = b->dx[q] * b->dx[q] + b->dy[q] * b->dy[q] + b->dz[q] * b->dz[q];
    b->ri[q] = ri;
    b->rj[q] = rj;
    b->imi[q] = 1.0 / (2500.0 * 4.18879 * ri * ri * ri);
    b->imj[q] = 1.0 / (2500.0 * 4.18879 * rj * rj * rj);
    const int fresh = uniform(0, 1) < 0.2, loaded = uniform(0, 1) < 0.5; /* loaded: slides or hits the rolling limit */
    for (int a = 0; a < 3; a++) {
        b->dv[a][q] = uniform(-0.2, 0.2);
        b->wi[a][q] = uniform(-100, 100);
        b->wj[a][q] = uniform(-100, 100);
        h0[a] = fresh ? 0.0 : uniform(-1, 1) * (loaded ? 1e-4 : 1e-7);
        h0[3 + a] = fresh ? 0.0 : uniform(-1, 1) * (loaded ? 1e-3 : 1e-8);
    }
    for (int a = 0; a < 6; a++) b->h[a][q] = h0[a];
}

#define N_OUT 16 /* force 3, torque on i 3, torque on j 3, histories 6, overlap */

/* The scalar reference, as the engine computed pair contacts before batching (and the normal,
 * n, to classify the regime). */
static void reference(const pair_batch *b, int q, const double *h0, double dt, double *out, double *n)
{
    contact_in in;
    dem_pair_batch_contact_in(b, q, &in);
    double h[6];
    memcpy(h, h0, sizeof h);
    contact_out o;
    contact_law(b->pp[q], &in, dt, h, h + 3, &o);
    contact_torques(&o, in.ci, in.cj, out + 3, out + 6);
    for (int a = 0; a < 3; a++) {
        out[a] = o.force[a];
        n[a] = in.n[a];
    }
    memcpy(out + 9, h, sizeof h);
    out[15] = in.overlap;
}

/* ...; *pulls counts the contacts whose net normal force attracts (cohesion at work). */
static void check_batch(const pair_props *types, int n_types, int m, int *slides, int *limits, int *pulls)
{
    static pair_batch b;
    static double h0[DEM_PAIR_BATCH][6];
    const double dt = 1e-6;
    memset(&b, 0, sizeof b);
    b.m = m;
    for (int q = 0; q < m; q++) random_contact(&b, q, &types[q % n_types], h0[q]);
    /* one pair type: every other batch is told so by the caller (one particle material), as
     * the sweep does; the others find it out */
    const int told = n_types == 1 && m % 2;
    dem_pair_batch_props(&b, told ? types : NULL);
    assert_true((b.uniform != NULL) == (n_types == 1 || m == 1));
    assert_int_equal(b.has_effects, any_effects(types, n_types, m));
    dem_pair_batch_law(&b, dt);
    for (int q = 0; q < m; q++) {
        double want[N_OUT], got[N_OUT], n[3];
        reference(&b, q, h0[q], dt, want, n);
        for (int a = 0; a < 3; a++) {
            got[a] = b.force[a][q];
            got[3 + a] = b.ti[a][q];
            got[6 + a] = b.tj[a][q];
        }
        for (int a = 0; a < 6; a++) got[9 + a] = b.h[a][q];
        got[15] = b.overlap[q];
        for (int v = 0; v < N_OUT; v++) {
            if (memcmp(&want[v], &got[v], sizeof(double)) != 0)
                fail_msg("contact %d (pair type %d), value %d: batch %.17g, scalar law %.17g", q, q % n_types, v, got[v], want[v]);
        }
        /* count the regimes the random draw reached, so the test cannot pass on easy cases only */
        const double tn = want[0] * n[0] + want[1] * n[1] + want[2] * n[2];
        const double ft[3] = {want[0] - tn * n[0], want[1] - tn * n[1], want[2] - tn * n[2]};
        const double ftn = sqrt(ft[0] * ft[0] + ft[1] * ft[1] + ft[2] * ft[2]);
        if (tn > 0 && fabs(ftn - types[q % n_types].def.friction * tn) <= 1e-9 * tn) (*slides)++;
        if (tn < 0) (*pulls)++;
        /* rolling torque: the part of the torques on i and j that is not the lever arms' */
        double ci = b.ri[q] - 0.5 * want[15], cj = b.rj[q] - 0.5 * want[15], m[3];
        for (int a = 0; a < 3; a++) m[a] = (cj * want[3 + a] - ci * want[6 + a]) / (ci + cj);
        const double mr = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        const double mmax = types[q % n_types].def.rolling_friction * (b.ri[q] * b.rj[q] / (b.ri[q] + b.rj[q])) * tn;
        if (mmax > 0 && fabs(mr - mmax) <= 1e-9 * mmax) (*limits)++;
    }
}

static void test_batch_equals_scalar_law(void **state)
{
    (void)state;
    const pair_props types[4] = {props(0.5, 0.0, DEM_ROLLING_EPSD2, 3e6), props(0.3, 0.1, DEM_ROLLING_EPSD2, 3e6),
                                 props(0.0, 0.4, DEM_ROLLING_EPSD2, 1e8), props(1.0, 0.05, DEM_ROLLING_EPSD2, 5e5)};
    int slides = 0, limits = 0, pulls = 0;
    for (int round = 0; round < 50; round++)
        check_batch(types, 4, round ? 1 + round % DEM_PAIR_BATCH : DEM_PAIR_BATCH, &slides, &limits, &pulls);
    for (int round = 0; round < 20; round++) check_batch(types, 4, DEM_PAIR_BATCH, &slides, &limits, &pulls);
    for (int round = 0; round < 40; round++) check_batch(types + round % 4, 1, DEM_PAIR_BATCH - round % 2, &slides, &limits, &pulls);
    assert_int_equal(pulls, 0); /* no effects: the normal force never attracts */
    assert_true(slides > 50);  /* the Coulomb cap was exercised */
    assert_true(limits > 50);  /* and the rolling limit */
}

static void test_every_rolling_model_in_the_batch(void **state)
{
    (void)state;
    const pair_props types[3] = {props(0.5, 0.2, DEM_ROLLING_CDT, 3e6), props(0.4, 0.1, DEM_ROLLING_EPSD, 3e6),
                                 props(0.6, 0.3, DEM_ROLLING_EPSD2, 3e6)};
    int slides = 0, limits = 0, pulls = 0;
    for (int round = 0; round < 20; round++) check_batch(types, 3, DEM_PAIR_BATCH, &slides, &limits, &pulls);
    for (int round = 0; round < 20; round++) check_batch(types + round % 2, 1, DEM_PAIR_BATCH - round % 2, &slides, &limits, &pulls);
    assert_true(slides > 20 && limits > 20);
}

/* Effects in the batch: SJKR cohesion (a normal force) and twisting resistance (a torque), each
 * alone and together, with every rolling case (none, EPSD2, CDT, EPSD), alone in a batch (the
 * uniform loop) and mixed with dry pair types. */
static void test_effects_in_the_batch(void **state)
{
    (void)state;
    /* cohesion alone takes the batch kernels (a uniform batch), the others the per-contact stage */
    const pair_props types[8] = {with_effects(props(0.5, 0.0, DEM_ROLLING_EPSD2, 3e6), 5e4, 0.0),
                                 with_effects(props(0.3, 0.1, DEM_ROLLING_EPSD2, 3e6), 1e5, 0.3),
                                 props(0.4, 0.1, DEM_ROLLING_EPSD2, 3e6),
                                 with_effects(props(0.6, 0.2, DEM_ROLLING_CDT, 3e6), 0.0, 0.5),
                                 with_effects(props(0.5, 0.1, DEM_ROLLING_EPSD, 3e6), 2e4, 0.2),
                                 with_effects(props(0.7, 0.0, DEM_ROLLING_EPSD2, 1e8), 0.0, 0.4),
                                 with_effects(props(0.45, 0.15, DEM_ROLLING_EPSD2, 3e6), 8e4, 0.0),
                                 with_effects(props(0.35, 0.2, DEM_ROLLING_CDT, 3e6), 3e4, 0.0)};
    int slides = 0, limits = 0, pulls = 0;
    for (int round = 0; round < 30; round++) check_batch(types, 3, 1 + round % DEM_PAIR_BATCH, &slides, &limits, &pulls);
    for (int round = 0; round < 30; round++) check_batch(types, 8, DEM_PAIR_BATCH, &slides, &limits, &pulls);
    for (int round = 0; round < 80; round++) check_batch(types + round % 8, 1, DEM_PAIR_BATCH - round % 2, &slides, &limits, &pulls);
    assert_true(pulls > 50);  /* cohesion outweighed the elastic force in some contacts */
    assert_true(slides > 20 && limits > 20);
}

/* Wall contacts: a sphere against a moving, turning surface, as dem_mesh_contacts_rows batches
 * them, against the scalar law it replaced. */
static void check_wall_batch(const pair_props *types, int n_types, int m, int *slides, int *pulls)
{
    static pair_batch b;
    static double h0[DEM_PAIR_BATCH][6], v[DEM_PAIR_BATCH][3], vw[DEM_PAIR_BATCH][3];
    const double dt = 1e-6;
    memset(&b, 0, sizeof b);
    b.m = m;
    for (int q = 0; q < m; q++) {
        random_contact(&b, q, &types[q % n_types], h0[q]);
        const double r = b.ri[q], len = sqrt(b.r2[q]);
        b.dx[q] /= len; /* the unit normal */
        b.dy[q] /= len;
        b.dz[q] /= len;
        b.dist[q] = r * (1.0 - uniform(1e-5, 0.02));
        for (int a = 0; a < 3; a++) {
            v[q][a] = uniform(-0.2, 0.2);
            vw[q][a] = uniform(-0.1, 0.1);
            b.dv[a][q] = v[q][a] - vw[q][a];
            b.wj[a][q] = uniform(-10, 10); /* the wall's spin */
        }
    }
    dem_pair_batch_props(&b, NULL);
    assert_int_equal(b.has_effects, any_effects(types, n_types, m));
    dem_wall_batch_law(&b, dt);
    for (int q = 0; q < m; q++) {
        const double n[3] = {b.dx[q], b.dy[q], b.dz[q]}, w[3] = {b.wi[0][q], b.wi[1][q], b.wi[2][q]},
                     ww[3] = {b.wj[0][q], b.wj[1][q], b.wj[2][q]};
        contact_in c;
        const double ci = wall_contact_in(&c, n, b.dist[q], b.ri[q], b.imi[q], v[q], w, vw[q], ww);
        double h[6], want[12], got[12];
        memcpy(h, h0[q], sizeof h);
        contact_out o;
        contact_law(b.pp[q], &c, dt, h, h + 3, &o);
        for (int a = 0; a < 3; a++) {
            want[a] = o.force[a];
            want[3 + a] = -ci * o.cross[a] + o.mr[a];
            got[a] = b.force[a][q];
            got[3 + a] = b.ti[a][q];
        }
        for (int a = 0; a < 6; a++) {
            want[6 + a] = h[a];
            got[6 + a] = b.h[a][q];
        }
        for (int k = 0; k < 12; k++)
            if (memcmp(&want[k], &got[k], sizeof(double)) != 0)
                fail_msg("wall contact %d, value %d: batch %.17g, scalar law %.17g", q, k, got[k], want[k]);
        const double fn = want[0] * n[0] + want[1] * n[1] + want[2] * n[2];
        const double ft[3] = {want[0] - fn * n[0], want[1] - fn * n[1], want[2] - fn * n[2]};
        if (fn > 0 && fabs(sqrt(ft[0] * ft[0] + ft[1] * ft[1] + ft[2] * ft[2]) - types[q % n_types].def.friction * fn) <= 1e-9 * fn)
            (*slides)++;
        if (fn < 0) (*pulls)++;
    }
}

static void test_wall_batch_equals_scalar_law(void **state)
{
    (void)state;
    const pair_props types[5] = {props(0.5, 0.0, DEM_ROLLING_EPSD2, 3e6), props(0.3, 0.1, DEM_ROLLING_EPSD2, 3e6),
                                 props(0.8, 0.05, DEM_ROLLING_EPSD2, 1e8), props(0.4, 0.2, DEM_ROLLING_CDT, 3e6),
                                 props(0.6, 0.1, DEM_ROLLING_EPSD, 3e6)};
    int slides = 0, pulls = 0;
    for (int round = 0; round < 30; round++) check_wall_batch(types, 3, 1 + round % DEM_PAIR_BATCH, &slides, &pulls);
    for (int round = 0; round < 30; round++) check_wall_batch(types + round % 5, 1, DEM_PAIR_BATCH, &slides, &pulls);
    for (int round = 0; round < 10; round++) check_wall_batch(types, 5, DEM_PAIR_BATCH, &slides, &pulls); /* models mixed */
    assert_true(slides > 50);
    assert_int_equal(pulls, 0);
    /* with effects: cohesion and twisting against the wall, alone and mixed with dry types */
    const pair_props fx[4] = {with_effects(props(0.5, 0.0, DEM_ROLLING_EPSD2, 3e6), 5e4, 0.0),
                              with_effects(props(0.3, 0.1, DEM_ROLLING_EPSD2, 3e6), 1e5, 0.3), props(0.4, 0.1, DEM_ROLLING_CDT, 3e6),
                              with_effects(props(0.6, 0.2, DEM_ROLLING_EPSD, 3e6), 0.0, 0.5)};
    slides = 0;
    for (int round = 0; round < 30; round++) check_wall_batch(fx, 4, 1 + round % DEM_PAIR_BATCH, &slides, &pulls);
    for (int round = 0; round < 40; round++) check_wall_batch(fx + round % 4, 1, DEM_PAIR_BATCH - round % 2, &slides, &pulls);
    assert_true(pulls > 50 && slides > 20);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_batch_equals_scalar_law),
        cmocka_unit_test(test_every_rolling_model_in_the_batch),
        cmocka_unit_test(test_effects_in_the_batch),
        cmocka_unit_test(test_wall_batch_equals_scalar_law),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
