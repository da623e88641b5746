/* The effect registry and its members against closed forms.
 * SJKR cohesion: F = -k_c A added to the Hertz normal force, A = pi a^2 the lens circle of two
 * spheres, pi (R^2 - r^2) against a wall. Static configurations, so the expected force is plain
 * arithmetic: tolerance 1e-12.
 * Twisting resistance: a sphere resting on a plane and spinning about the vertical slows at the
 * constant torque mu_t R m g (w = w0 - (5/2) mu_t g t / R) until the viscous branch of the law
 * takes over, then creeps to rest exponentially without turning back.
 * SJKR in motion: cohesion acts only while two spheres overlap and does opposite work on the
 * way in and out, so a collision (damped, restitution 0.83) can only lose kinetic energy: at
 * every step the kinetic energy stays below its value before contact plus the cohesive well
 * depth k_c pi R* delta^2 at the current overlap, and after the contact at most the energy
 * before; a slow pair sticks (the well is deeper than its energy), a fast one rebounds with
 * less than e^2 of it. Unequal soft spheres (radii 0.98 and 1.86 mm, E = 5 MPa, k_c 8.3e4:
 * the angle-of-repose store's failing corner) at 0.05, 1 and 3 m/s. Tolerance 1e-9 of the
 * initial energy (round-off of the energy sums over ~10^4 steps).
 * A tangential-force kernel (no member uses one yet): its force adds to the contact's force
 * and its torques follow from the lever arms, as the friction's do (arithmetic: 1e-12). */
#include "test_util.h"
#include "contact_law.h"

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

/* Every parameter's published range holds its neutral value, and dem_pair_set_effect accepts
 * exactly that closed range: both ends pass, the next double outside each end is refused. */
static void test_param_range_is_what_pair_set_effect_accepts(void **st)
{
    (void)st;
    dem_material mat;
    dem_domain *d = make_domain(0.01, 1e-6, E, 0.5, 0.5, &mat);
    for (int i = 0; i < dem_effect_count(); i++) {
        const char *name;
        int np;
        assert_ok(dem_effect_info(i, &name, NULL, &np));
        for (int p = 0; p < np; p++) {
            double lo, hi, neutral, v[8];
            assert_true(np <= 8);
            assert_ok(dem_effect_param_range(i, p, &lo, &hi));
            assert_ok(dem_effect_param_info(i, p, NULL, NULL, &neutral));
            assert_true(lo <= neutral && neutral <= hi && lo < hi);
            for (int k = 0; k < np; k++) assert_ok(dem_effect_param_info(i, k, NULL, NULL, &v[k]));
            const double inside[2] = {lo, hi}, outside[2] = {nextafter(lo, -INFINITY), nextafter(hi, INFINITY)};
            for (int s = 0; s < 2; s++) {
                v[p] = inside[s];
                assert_ok(dem_pair_set_effect(d, mat, mat, name, v, np));
                v[p] = outside[s];
                assert_int_equal(dem_pair_set_effect(d, mat, mat, name, v, np), DEM_ERR_INVALID_ARGUMENT);
            }
        }
    }
    assert_int_equal(dem_effect_param_range(dem_effect_count(), 0, NULL, NULL), DEM_ERR_UNKNOWN_EFFECT);
    assert_int_equal(dem_effect_param_range(0, -1, NULL, NULL), DEM_ERR_INVALID_ARGUMENT);
    dem_domain_destroy(d);
}

static double pair_force_z(double kc, double delta)
{
    dem_material mat;
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
    dem_material mats[2] = {mat, mat};
    assert_ok(dem_particles_add(d, 2, pos, rad, mats, NULL, NULL, NULL));
    assert_ok(dem_domain_step(d, 0)); /* forces of the current state */
    assert_ok(dem_particles_get_forces(d, f, dem_particle_count(d)));
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
    dem_material mat;
    dem_plane_wall wall;
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
    assert_ok(dem_particles_get_forces(d, f, dem_particle_count(d)));
    double hertz = 4.0 / 3.0 * es * sqrt(R * delta) * delta, r = R - delta;
    assert_close(f[2], hertz - KC * M_PI * (R * R - r * r), 1e-12, 0);
    assert_ok(dem_plane_wall_force(d, wall, fw));
    assert_close(fw[2], -f[2], 1e-14, 0);
    /* neutral value switches the effect off */
    kc = 0.0;
    assert_ok(dem_pair_set_effect(d, mat, mat, "cohesion_sjkr", &kc, 1));
    assert_ok(dem_domain_step(d, 0));
    assert_ok(dem_particles_get_forces(d, f, dem_particle_count(d)));
    assert_close(f[2], hertz, 1e-12, 0);
    /* bad input */
    kc = -1;
    assert_int_equal(dem_pair_set_effect(d, mat, mat, "cohesion_sjkr", &kc, 1), DEM_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(dem_domain_last_error(d), "cohesion_energy_density"));
    assert_int_equal(dem_pair_set_effect(d, mat, mat, "no_such_effect", &kc, 1), DEM_ERR_UNKNOWN_EFFECT);
    assert_int_equal(dem_pair_set_effect(d, mat, mat, "cohesion_sjkr", &kc, 2), DEM_ERR_INVALID_ARGUMENT);
    dem_domain_destroy(d);
}

/* A sphere of radius TR inserted at its static Hertz overlap on the floor, spinning at W0
 * about z, with twisting friction mu_t; steps to time t_end, returns w_z(t_half) and w_z(t_end)
 * and the smallest w_z seen (a reversal would make it negative). */
static const double TR = 0.01, TE = 1e7, TNU = 0.25, TRHO = 2500.0, G = 9.81, W0 = 20.0;

static void spin_down(double mu_t, double t_half, double t_end, double *w_half, double *w_end, double *w_min)
{
    dem_domain_def def = dem_default_domain_def();
    for (int a = 0; a < 3; a++) {
        def.lo[a] = 0.0;
        def.hi[a] = 0.1;
        def.gravity[a] = 0.0;
    }
    def.gravity[2] = -G;
    def.dt = 1e-5; /* Rayleigh time 8.6e-4 s, Hertz contact time ~2e-3 s */
    def.insert_overlap_ratio = 0.5;
    dem_domain *d;
    assert_int_equal(dem_domain_create(&def, &d, NULL, 0), DEM_OK);
    dem_material_def m = dem_default_material_def();
    m.youngs_modulus = TE;
    m.poisson_ratio = TNU;
    m.density = TRHO;
    dem_material mat;
    dem_plane_wall wall;
    assert_ok(dem_material_create(d, &m, &mat));
    dem_pair_def p = dem_default_pair_def();
    p.rolling_friction = 0.0;
    assert_ok(dem_pair_set(d, mat, mat, &p));
    if (mu_t > 0) assert_ok(dem_pair_set_effect(d, mat, mat, "twisting_resistance", &mu_t, 1));
    dem_plane_wall_def pw = dem_default_plane_wall_def();
    pw.material = mat;
    assert_ok(dem_plane_wall_add(d, &pw, &wall));
    const double mass = TRHO * 4.0 / 3.0 * M_PI * TR * TR * TR;
    const double delta = pow(mass * G / (4.0 / 3.0 * e_star_same(TE, TNU) * sqrt(TR)), 2.0 / 3.0); /* at rest */
    double pos[3] = {0.05, 0.05, TR - delta}, r = TR, w[3] = {0.0, 0.0, W0}, om[3];
    assert_ok(dem_particles_add(d, 1, pos, &r, &mat, NULL, w, NULL));
    *w_min = W0;
    const int64_t n_half = (int64_t)llround(t_half / def.dt), n_end = (int64_t)llround(t_end / def.dt);
    for (int64_t s = 1; s <= n_end; s++) {
        assert_ok(dem_domain_step(d, 1));
        assert_ok(dem_particles_get_angular_velocities(d, om, dem_particle_count(d)));
        if (om[2] < *w_min) *w_min = om[2];
        if (s == n_half) *w_half = om[2];
    }
    *w_end = om[2];
    dem_domain_destroy(d);
}

/* Kinetic energy (translation + rotation) of the two spheres of a collision run. */
static double two_sphere_energy(dem_domain *d, const double *m, const double *r)
{
    double v[6], w[6], k = 0.0;
    assert_ok(dem_particles_get_velocities(d, v, 2));
    assert_ok(dem_particles_get_angular_velocities(d, w, 2));
    for (int i = 0; i < 2; i++)
        for (int a = 0; a < 3; a++) k += 0.5 * m[i] * (v[3 * i + a] * v[3 * i + a] + 0.4 * r[i] * r[i] * w[3 * i + a] * w[3 * i + a]);
    return k;
}

/* Head-on collision at relative speed u; returns the kinetic energy after / before (the pair
 * separated, or after 20 ms if it stuck; *stuck says which). */
static double sjkr_collision(double u, int *stuck)
{
    const double r[2] = {0.976e-3, 1.859e-3}, rho = 2500.0, e = 0.83, kc = 8.3e4, rs = r[0] * r[1] / (r[0] + r[1]);
    const double m[2] = {sphere_mass(rho, r[0]), sphere_mass(rho, r[1])};
    dem_domain_def def = dem_default_domain_def(); /* not make_domain(): the 3 m/s impact peaks at 0.27 of */
    def.gravity[2] = 0;                            /* the small radius, near the default 0.3 runaway bound */
    def.max_overlap_ratio = 0.9;
    dem_domain *d;
    assert_int_equal(dem_domain_create(&def, &d, NULL, 0), DEM_OK);
    dem_material_def md = dem_default_material_def();
    md.youngs_modulus = 5e6;
    dem_material mat;
    assert_ok(dem_material_create(d, &md, &mat));
    dem_pair_def pd = dem_default_pair_def();
    pd.restitution = e;
    pd.friction = 0.4;
    assert_ok(dem_pair_set(d, mat, mat, &pd));
    assert_ok(dem_pair_set_effect(d, mat, mat, "cohesion_sjkr", &kc, 1));
    const double x0 = 0.005, gap = 1e-5;
    double pos[6] = {x0 - r[0] - gap, x0, x0, x0 + r[1], x0, x0}, rad[2] = {r[0], r[1]};
    double vel[6] = {u * m[1] / (m[0] + m[1]), 0, 0, -u * m[0] / (m[0] + m[1]), 0, 0};
    dem_material mats[2] = {mat, mat};
    assert_ok(dem_particles_add(d, 2, pos, rad, mats, vel, NULL, NULL));
    dem_timestep_info ti;
    assert_ok(dem_domain_timestep_info(d, &ti));
    assert_ok(dem_domain_set_dt(d, ti.suggested_dt));
    const double k0 = two_sphere_energy(d, m, r);
    int touched = 0;
    double k = k0;
    for (double t = 0; t < 0.02; t += ti.suggested_dt) {
        assert_ok(dem_domain_step(d, 1));
        double x[6];
        assert_ok(dem_particles_get_positions(d, x, 2));
        const double delta = r[0] + r[1] - fabs(x[3] - x[0]);
        k = two_sphere_energy(d, m, r);
        const double well = delta > 0 ? kc * M_PI * rs * delta * delta : 0.0;
        assert_true(k <= k0 + well + 1e-9 * k0);
        if (delta > 0) touched = 1;
        else if (touched && delta < -1e-6) break; /* apart again */
    }
    assert_true(touched);
    assert_true(k <= k0 * (1 + 1e-9));
    double x[6];
    assert_ok(dem_particles_get_positions(d, x, 2));
    *stuck = r[0] + r[1] - fabs(x[3] - x[0]) > 0;
    dem_domain_destroy(d);
    return k / k0;
}

static void test_sjkr_collision_loses_energy(void **st)
{
    (void)st;
    int stuck;
    double slow = sjkr_collision(0.05, &stuck);
    assert_true(stuck);
    assert_true(slow < 0.01);
    for (int i = 0; i < 2; i++) {
        double fast = sjkr_collision(i ? 3.0 : 1.0, &stuck);
        if (getenv("DEM_TEST_VERBOSE")) printf("  SJKR collision at %g m/s: energy after / before %.4f\n", i ? 3.0 : 1.0, fast);
        assert_false(stuck);
        assert_true(fast < 0.83 * 0.83 && fast > 0.3);
    }
}

static void test_twisting_spin_down(void **st)
{
    (void)st;
    /* the closed form: Coulomb at the cap mu_t R m g down to w* = cap / c_t, then the viscous
     * branch c_t w alone: w = w* exp(-(t - t*) / tau), tau = I / c_t */
    const double mu_t = 0.3, mass = TRHO * 4.0 / 3.0 * M_PI * TR * TR * TR, inertia = 0.4 * mass * TR * TR;
    const double delta = pow(mass * G / (4.0 / 3.0 * e_star_same(TE, TNU) * sqrt(TR)), 2.0 / 3.0);
    const double g_star = TE / (4.0 * (2.0 - TNU) * (1.0 + TNU));
    const double k_tw = (2.0 / 3.0) * 8.0 * g_star * sqrt(TR * delta) * TR * delta, c_t = 2.0 * sqrt(k_tw * inertia);
    const double cap = mu_t * TR * mass * G, alpha = cap / inertia, w_star = cap / c_t, tau = inertia / c_t;
    const double t_star = (W0 - w_star) / alpha; /* 21.6 ms here; tau = 11 ms */
    const double t_half = llround(0.5 * t_star / 1e-5) * 1e-5, t_end = llround((t_star + 2.0 * tau) / 1e-5) * 1e-5;
    double w_half, w_end, w_min;
    spin_down(mu_t, t_half, t_end, &w_half, &w_end, &w_min);
    /* Coulomb phase: the normal force is m g (a static start), the torque constant; 1e-5 is
     * round-off plus the first step's half-kick */
    assert_close(w_half, W0 - alpha * t_half, 1e-5, 0);
    /* viscous phase: explicit integration of the decay, dt / tau = 1e-3: within 2e-3 */
    assert_close(w_end, w_star * exp(-(t_end - t_star) / tau), 2e-3, 0);
    assert_true(w_min > 0.0); /* it creeps to rest, never turns back */
    /* neutral value: no twisting torque at all, the spin stays W0 to round-off */
    spin_down(0.0, t_half, t_end, &w_half, &w_end, &w_min);
    assert_close(w_end, W0, 1e-12, 0);
}

/* A made-up effect with a tangential kernel: a viscous drag -c vt. */
static void drag(const dem_effect_contact *c, const double *params, double force[3])
{
    for (int a = 0; a < 3; a++) force[a] -= params[0] * c->vt[a];
}

static void test_tangential_kernel(void **st)
{
    (void)st;
    const dem_effect_desc desc = {.name = "drag", .n_params = 1, .tangential_force = drag};
    /* two spheres touching along z, i above j, sliding in x and spinning: the contact's input */
    const double dv[3] = {0.02, -0.01, 0.0}, wi[3] = {1.0, 2.0, 0.5}, wj[3] = {0.0, -1.0, 0.0};
    contact_in c;
    pair_geometry(&c, 0.0, 0.0, 1.99e-3, 1.99e-3 * 1.99e-3, R, R, 1.0 / 1e-5, 1.0 / 1e-5, dv, wi, wj);
    double vn = c.vc[0] * c.n[0] + c.vc[1] * c.n[1] + c.vc[2] * c.n[2], vt[3];
    tangential_velocity(&c, vn, vt);
    dem_effect_contact ec = {.normal_force = 1.0};
    for (int a = 0; a < 3; a++) ec.vt[a] = vt[a];
    const double cdrag = 3.0, ft0[3] = {0.1, 0.2, 0.0};
    double ft[3] = {ft0[0], ft0[1], ft0[2]}, mr[3] = {0.0, 0.0, 0.0}, fn = 1.0;
    effect_apply(&desc, &cdrag, &ec, &fn, ft, mr);
    assert_true(fn == 1.0 && mr[0] == 0.0 && mr[1] == 0.0 && mr[2] == 0.0); /* only the force moved */
    double cross[3], ti[3], tj[3];
    tangential_cross(c.n, ft, cross);
    torques_from(cross, mr, c.ci, c.cj, ti, tj);
    for (int a = 0; a < 3; a++) {
        const double f = ft0[a] - cdrag * vt[a];
        assert_true(fabs(ft[a] - f) <= 1e-12 * (fabs(f) + 1e-3));
    }
    /* torque on i: -(R - delta/2) n x F_t with n = +z: (F_y, -F_x, 0) times the lever arm */
    const double arm = R - 0.5 * (2 * R - 1.99e-3);
    assert_true(fabs(ti[0] - arm * ft[1]) <= 1e-12 && fabs(ti[1] + arm * ft[0]) <= 1e-12 && ti[2] == 0.0);
    for (int a = 0; a < 3; a++) assert_true(fabs(tj[a] - ti[a]) <= 1e-15); /* equal spheres: equal arms */
    assert_true(fabs(vt[2]) <= 1e-15 && fabs(vt[0]) > 0.0); /* the kernel saw the tangential velocity */
}

/* Every effect's batch kernel (where it has one) against its scalar kernel: pair and wall
 * contacts at random overlaps and radii, bitwise (tolerance zero: the batch loop of the contact
 * law relies on the two giving the same IEEE result, tests/c/test_batch.c). */
static void test_batch_kernels_match(void **st)
{
    (void)st;
    uint64_t x = 0x9E3779B97F4A7C15ull;
#define RAND01() (x ^= x << 13, x ^= x >> 7, x ^= x << 17, (double)(x >> 11) / 9007199254740992.0)
    enum { M = 61 };
    int checked = 0;
    for (int e = 0; e < dem_effect_count(); e++) {
        const dem_effect_desc *ed = dem_effect_get(e);
        if (!ed->normal_force_batch) continue;
        assert_non_null(ed->normal_force); /* a batch kernel is the batch form of a scalar one */
        assert_null(ed->tangential_force);
        assert_null(ed->torque);
        double params[DEM_MAX_EFFECT_PARAMS];
        for (int k = 0; k < ed->n_params; k++) params[k] = ed->params[k].neutral + 1e4 * (1.0 + RAND01());
        for (int wall = 0; wall < 2; wall++) {
            double n[3][M], overlap[M], dist[M], ri[M], rj[M], fn[M], r_eff[M], kt[M], total[M], want[M];
            for (int q = 0; q < M; q++) {
                ri[q] = 1e-3 * (0.5 + RAND01());
                rj[q] = wall ? 0.0 : 1e-3 * (0.5 + RAND01());
                overlap[q] = 0.05 * ri[q] * RAND01();
                dist[q] = ri[q] + rj[q] - overlap[q];
                n[0][q] = 1.0, n[1][q] = n[2][q] = 0.0;
                fn[q] = RAND01();
                r_eff[q] = wall ? ri[q] : ri[q] * rj[q] / (ri[q] + rj[q]);
                kt[q] = 1e4 * RAND01();
                total[q] = fn[q];
                dem_effect_contact c = {{1.0, 0.0, 0.0}, overlap[q], dist[q], ri[q], rj[q], fn[q], r_eff[q], {0, 0, 0}, 1.0, kt[q], {0, 0, 0}};
                want[q] = fn[q] + ed->normal_force(&c, params);
            }
            const dem_effect_batch b = {M, {n[0], n[1], n[2]}, overlap, dist, ri, rj, fn, r_eff, kt};
            ed->normal_force_batch(&b, params, total);
            for (int q = 0; q < M; q++)
                if (memcmp(&total[q], &want[q], sizeof(double)) != 0)
                    fail_msg("%s, %s contact %d: batch %.17g, scalar %.17g", ed->name, wall ? "wall" : "pair", q, total[q], want[q]);
            checked++;
        }
    }
#undef RAND01
    assert_true(checked >= 2); /* cohesion_sjkr has one, pair and wall */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_registry),
        cmocka_unit_test(test_param_range_is_what_pair_set_effect_accepts),
        cmocka_unit_test(test_sjkr_pair),
        cmocka_unit_test(test_sjkr_wall_and_switch_off),
        cmocka_unit_test(test_sjkr_collision_loses_energy),
        cmocka_unit_test(test_twisting_spin_down),
        cmocka_unit_test(test_tangential_kernel),
        cmocka_unit_test(test_batch_kernels_match),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
