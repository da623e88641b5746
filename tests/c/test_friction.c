/* Coulomb friction in gross sliding against rigid-body impact theory (Chung & Ooi 2011,
 * tests 5 and 6): while the contact point slips for the whole impact, the tangential impulse is
 * exactly mu times the normal impulse, whatever the restitution. Closed forms for a sphere of
 * mass m, radius R, inertia 2/5 m R^2 meeting a plane (or an identical sphere) at normal speed
 * V_n with restitution e:
 *   normal impulse J = m* (1 + e) V_n, tangential impulse mu J against the slip,
 *   so a sphere spinning onto a plane rebounds with v_t = mu (1 + e) V_n,
 *   an oblique impact keeps v_t,out / v_t,in = 1 - mu (1 + e) V_n / V_t (tangential
 *   restitution 1 - mu (1 + e) / tan(theta)) and leaves spinning at 5 mu (1 + e) V_n / (2 R).
 * The runs use an aluminium alloy sphere (R = 0.1 m, E = 70 GPa, nu = 0.33, 2700 kg/m^3),
 * mu = 0.4, no gravity, dt = t_c / 200, for e = 0.1 ... 0.9.
 * Tolerances: 1 % against the nominal e (the delivered restitution is within 0.6 % of the
 * requested one, test_restitution.c; 1 + e then moves by < 0.3 %, and the lever arm R - delta/2
 * differs from R by ~1e-4), 1e-9 for the impulse ratio against the *measured* normal impulse
 * on a plane (round-off only: the cap makes |F_t| = mu F_n at every sliding step). */
#include "test_util.h"

static const double R = 0.1, RHO = 2700.0, E_AL = 7e10, NU_AL = 0.33, MU = 0.4, VN = 0.2;
static const double E_LIST[] = {0.1, 0.3, 0.5, 0.7, 0.9};

typedef struct impact {
    dem_domain *d;
    double dt;
    int steps;
} impact;

/* A domain with one aluminium material (restitution e, friction MU), dt = t_c / 200 for a
 * collision at VN with effective radius r_eff and effective mass m_eff. */
static impact make_impact(double e, double r_eff, double m_eff)
{
    impact im = {0};
    dem_domain_def def = dem_default_domain_def();
    for (int a = 0; a < 3; a++) {
        def.lo[a] = 0.0;
        def.hi[a] = 2.0;
        def.gravity[a] = 0.0;
    }
    const double es = e_star_same(E_AL, NU_AL);
    const double tc = 2.94328 * hertz_max_overlap(m_eff, VN, es, r_eff) / VN;
    def.dt = tc / 200.0;
    char msg[256];
    assert_ok(dem_domain_create(&def, &im.d, msg, sizeof msg));
    dem_material_def m = dem_default_material_def();
    m.youngs_modulus = E_AL;
    m.poisson_ratio = NU_AL;
    m.density = RHO;
    dem_material mat;
    assert_ok(dem_material_create(im.d, &m, &mat));
    dem_pair_def p = dem_default_pair_def();
    p.restitution = e;
    p.friction = MU;
    p.rolling_friction = 0.0;
    assert_ok(dem_pair_set(im.d, mat, mat, &p));
    im.dt = def.dt;
    im.steps = (int)(2.0 * tc / def.dt); /* the sphere starts 0.25 t_c away: all over by 2 t_c */
    return im;
}

/* Sphere on the floor z >= 0 (restitution e), starting VN * t_c / 4 above contact, with
 * velocity v and spin w. Steps one at a time and checks that the tangential force never has a
 * positive component along the slip velocity of the contact point; returns the velocity and
 * spin after the impact. */
static void floor_impact(double e, const double v[3], const double w[3], double vel[3], double om[3])
{
    impact im = make_impact(e, R, sphere_mass(RHO, R));
    dem_plane_wall wall;
    dem_material mat = {0};
    dem_plane_wall_def pw = dem_default_plane_wall_def();
    pw.material = mat;
    assert_ok(dem_plane_wall_add(im.d, &pw, &wall));
    double pos[3] = {1.0, 1.0, R + 0.25 * VN * 200.0 * im.dt}, r = R;
    assert_ok(dem_particles_add(im.d, 1, pos, &r, &mat, v, w, NULL));
    int in_contact = 0;
    for (int s = 0; s < im.steps; s++) {
        assert_ok(dem_domain_step(im.d, 1));
        double f[3];
        assert_ok(dem_particles_get_forces(im.d, f, dem_particle_count(im.d)));
        assert_ok(dem_particles_get_velocities(im.d, vel, dem_particle_count(im.d)));
        assert_ok(dem_particles_get_angular_velocities(im.d, om, dem_particle_count(im.d)));
        if (f[2] == 0.0) continue;
        in_contact++;
        /* slip of the contact point (at -R z from the centre): v + w x (-R z), tangential part */
        const double slip[2] = {vel[0] - R * om[1], vel[1] + R * om[0]};
        const double along = f[0] * slip[0] + f[1] * slip[1];
        const double scale = hypot(f[0], f[1]) * hypot(slip[0], slip[1]);
        if (along > 1e-12 * scale) {
            print_error("step %d: friction (%g, %g) has a component along the slip (%g, %g)\n", s, f[0], f[1],
                        slip[0], slip[1]);
            fail();
        }
    }
    assert_true(in_contact > 100); /* t_c / dt = 200 steps */
    dem_domain_destroy(im.d);
}

/* Chung & Ooi test 6, gross-sliding branch: a sphere spinning about a horizontal axis drops
 * onto the plane; its contact point slips (at R w = 1 m/s) for the whole impact. */
static void test_spinning_sphere_onto_plane(void **st)
{
    (void)st;
    for (size_t k = 0; k < sizeof E_LIST / sizeof E_LIST[0]; k++) {
        const double e = E_LIST[k], v[3] = {0, 0, -VN}, w[3] = {0, 10.0, 0};
        double vel[3], om[3];
        floor_impact(e, v, w, vel, om);
        assert_true(vel[2] > 0.0);
        /* slip velocity of the contact point is v_x - R w_y = -1 m/s: friction pushes +x */
        assert_close(vel[0], MU * (1.0 + e) * VN, 0.01, 0.0);
        assert_close(vel[0], MU * (VN + vel[2]), 1e-9, 0.0); /* exactly mu x the normal impulse */
        assert_close(vel[1], 0.0, 0.0, 1e-15);
    }
}

/* Chung & Ooi test 5 in the gross-sliding regime: an oblique impact without spin at
 * tan(theta) = V_t / V_n = 5 (> 3.5 mu (1 + e), so the contact slips throughout). */
static void test_oblique_impact_gross_sliding(void **st)
{
    (void)st;
    const double vt = 5.0 * VN;
    for (size_t k = 0; k < sizeof E_LIST / sizeof E_LIST[0]; k++) {
        const double e = E_LIST[k], v[3] = {vt, 0, -VN}, w[3] = {0, 0, 0};
        double vel[3], om[3];
        floor_impact(e, v, w, vel, om);
        assert_close(vel[0] / vt, 1.0 - MU * (1.0 + e) * VN / vt, 0.01, 0.0);
        /* rolling forward: w_y > 0 for motion along +x on a floor below */
        assert_close(om[1], 5.0 * MU * (1.0 + e) * VN / (2.0 * R), 0.01, 0.0);
        assert_close(vt - vel[0], MU * (VN + vel[2]), 1e-9, 0.0);
    }
}

/* The same between two identical spheres (the batched pair law): relative normal speed VN,
 * relative tangential speed 5 VN, no spin. Each sphere gets the impulse mu J with
 * J = (m / 2)(1 + e) V_n, so the relative tangential speed falls by mu (1 + e) V_n and each
 * sphere spins up by mu J R / I = 5 mu (1 + e) V_n / (4 R). */
static void test_oblique_pair_impact_gross_sliding(void **st)
{
    (void)st;
    const double vt = 5.0 * VN;
    for (size_t k = 0; k < sizeof E_LIST / sizeof E_LIST[0]; k++) {
        const double e = E_LIST[k], m = sphere_mass(RHO, R);
        impact im = make_impact(e, 0.5 * R, 0.5 * m);
        const double gap = 0.25 * VN * 200.0 * im.dt;
        /* the normal turns by ~V_t t_c / 2R = 4e-3 rad while the spheres slide past each other:
         * they start offset in x so that they pass each other in mid-contact, where the tilt
         * of the normal force cancels to first order (the closed forms assume a fixed normal) */
        const double tc = 200.0 * im.dt, half_offset = 0.5 * vt * (0.25 + 0.5) * tc;
        double pos[6] = {1.0 - half_offset, 1.0, 1.0 - R - gap / 2, 1.0 + half_offset, 1.0, 1.0 + R + gap / 2};
        double rad[2] = {R, R}, vel[6] = {vt / 2, 0, VN / 2, -vt / 2, 0, -VN / 2};
        dem_material mats[2] = {{0}, {0}};
        assert_ok(dem_particles_add(im.d, 2, pos, rad, mats, vel, NULL, NULL));
        double om[6], x[6], f[6];
        for (int s = 0; s < im.steps; s++) { /* friction never along the slip, as on the floor */
            assert_ok(dem_domain_step(im.d, 1));
            assert_ok(dem_particles_get_forces(im.d, f, dem_particle_count(im.d)));
            assert_ok(dem_particles_get_positions(im.d, x, dem_particle_count(im.d)));
            assert_ok(dem_particles_get_velocities(im.d, vel, dem_particle_count(im.d)));
            assert_ok(dem_particles_get_angular_velocities(im.d, om, dem_particle_count(im.d)));
            double n[3], dist = 0.0; /* from sphere 0 to sphere 1 */
            for (int a = 0; a < 3; a++) dist += (x[3 + a] - x[a]) * (x[3 + a] - x[a]);
            for (int a = 0; a < 3; a++) n[a] = (x[3 + a] - x[a]) / sqrt(dist);
            /* contact point velocity of 0 minus 1: v0 + w0 x (R n) - v1 - w1 x (-R n) */
            double u[3], ws[3];
            for (int a = 0; a < 3; a++) ws[a] = R * (om[a] + om[3 + a]);
            u[0] = vel[0] - vel[3] + ws[1] * n[2] - ws[2] * n[1];
            u[1] = vel[1] - vel[4] + ws[2] * n[0] - ws[0] * n[2];
            u[2] = vel[2] - vel[5] + ws[0] * n[1] - ws[1] * n[0];
            const double un = u[0] * n[0] + u[1] * n[1] + u[2] * n[2];
            const double fnn = f[0] * n[0] + f[1] * n[1] + f[2] * n[2];
            double along = 0.0, f2 = 0.0, u2 = 0.0;
            for (int a = 0; a < 3; a++) {
                const double ft = f[a] - fnn * n[a], ut = u[a] - un * n[a];
                along += ft * ut;
                f2 += ft * ft;
                u2 += ut * ut;
            }
            if (along > 1e-12 * sqrt(f2 * u2)) {
                print_error("step %d: friction on sphere 0 has a component along its slip\n", s);
                fail();
            }
        }
        const double vn_in = VN, vt_in = vt, vn_out = vel[5] - vel[2], vt_out = vel[0] - vel[3];
        assert_close(vt_out / vt_in, 1.0 - MU * (1.0 + e) * vn_in / vt_in, 0.01, 0.0);
        assert_close(vt_in - vt_out, MU * (vn_in + vn_out), 0.01, 0.0);
        assert_close(fabs(om[1]), 5.0 * MU * (1.0 + e) * vn_in / (4.0 * R), 0.01, 0.0);
        assert_close(om[1], om[4], 1e-12, 0.0); /* both turn the same way (their contact point is shared) */
        dem_domain_destroy(im.d);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_spinning_sphere_onto_plane),
        cmocka_unit_test(test_oblique_impact_gross_sliding),
        cmocka_unit_test(test_oblique_pair_impact_gross_sliding),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
