/* Static balance and stresses in a meshed box:
 *  - a settled column: the vertical force on floor + side walls equals the weight
 *    (momentum balance; tolerance 0.1 % as the issue asks, the residual is the bed's
 *    remaining momentum change);
 *  - a servo-loaded lid settles on its target (a few %) without oscillating;
 *  - the Love–Weber sigma_zz of the bulk under the lid equals lid force / lid area (5 %: the
 *    bulk's own weight adds ~1.7 %, wall friction takes a little).
 * Closed forms of the stress code itself: a single resting sphere under gravity. */
#include "mesh_util.h"

static const double R = 5e-4, L = 0.006, H = 0.02;

/* Particles and lid of material *mat; the box of a second material whose friction with the
 * particles is wall_friction. */
/* The L x L x H domain (dt 5 us) with one material *mat, restitution 0.2, friction 0.3. */
static dem_domain *column_domain(dem_material *mat)
{
    dem_domain_def def = dem_default_domain_def();
    for (int a = 0; a < 3; a++) {
        def.lo[a] = -0.001;
        def.hi[a] = (a == 2 ? H : L) + 0.001;
    }
    def.dt = 5e-6;
    dem_domain *d;
    char msg[256];
    assert_ok(dem_domain_create(&def, &d, msg, sizeof msg));
    dem_material_def md = dem_default_material_def();
    assert_ok(dem_material_create(d, &md, mat));
    dem_pair_def p = dem_default_pair_def();
    p.restitution = 0.2;
    p.friction = 0.3;
    assert_ok(dem_pair_set(d, *mat, *mat, &p));
    return d;
}

static dem_domain *column(dem_mesh_wall *mesh_box, dem_material *mat, int64_t *n, double wall_friction)
{
    dem_domain *d = column_domain(mat);
    dem_material_def md = dem_default_material_def();
    dem_pair_def p = dem_default_pair_def();
    p.restitution = 0.2;
    dem_material wall_mat;
    assert_ok(dem_material_create(d, &md, &wall_mat));
    p.friction = wall_friction;
    assert_ok(dem_pair_set(d, *mat, wall_mat, &p));
    *mesh_box = add_open_box(d, L, H, 1, wall_mat);
    /* 5 x 5 x 8 simple-cubic lattice, 1.15 mm spacing, slightly jittered so it collapses */
    int64_t k = 0;
    double pos[3 * 200], rad[200];
    dem_material mats[200];
    uint64_t rng = 7;
    for (int z = 0; z < 8; z++)
        for (int y = 0; y < 5; y++)
            for (int x = 0; x < 5; x++) {
                pos[3 * k] = 0.0007 + 1.15e-3 * x + 5e-5 * (test_urand(&rng) - 0.5);
                pos[3 * k + 1] = 0.0007 + 1.15e-3 * y + 5e-5 * (test_urand(&rng) - 0.5);
                pos[3 * k + 2] = 0.0006 + 1.15e-3 * z;
                rad[k] = R * (0.9 + 0.1 * test_urand(&rng));
                mats[k] = *mat;
                k++;
            }
    assert_ok(dem_particles_add(d, k, pos, rad, mats, NULL, NULL, NULL));
    *n = k;
    return d;
}

static double total_weight(dem_domain *d, int64_t n)
{
    double *r = malloc((size_t)n * sizeof(double)), w = 0.0;
    assert_ok(dem_particles_get_radii(d, r, dem_particle_count(d)));
    for (int64_t i = 0; i < n; i++) w += 2500.0 * 4.0 / 3.0 * M_PI * r[i] * r[i] * r[i] * 9.81;
    free(r);
    return w;
}

static void test_column_weight_on_walls(void **state)
{
    (void)state;
    dem_mesh_wall box;
    dem_material mat;
    int64_t n;
    dem_domain *d = column(&box, &mat, &n, 0.3);
    assert_ok(dem_domain_step(d, 40000)); /* 0.2 s: settled */
    double sum = 0.0;
    const int samples = 200;
    for (int s = 0; s < samples; s++) {
        assert_ok(dem_domain_step(d, 10));
        double f[3], t[3];
        assert_ok(dem_mesh_wall_force(d, box, NULL, f, t));
        sum += f[2];
    }
    double W = total_weight(d, n);
    /* the particles push the walls down by their weight */
    assert_close(-sum / samples, W, 1e-3, 0);
    dem_diagnostics dg;
    assert_ok(dem_domain_diagnostics(d, &dg));
    assert_true(dg.wall_contact_count > 25);
    /* per-triangle forces add up to the total */
    double tf[30 * 3], tot = 0.0, f[3];
    dem_mesh_info info;
    assert_ok(dem_mesh_wall_info(d, box, &info));
    assert_int_equal(info.triangle_count, 10);
    assert_ok(dem_mesh_wall_triangle_forces(d, box, tf, (int64_t)(sizeof tf / sizeof tf[0] / 3)));
    assert_ok(dem_mesh_wall_force(d, box, NULL, f, NULL));
    for (int t = 0; t < 10; t++) tot += tf[3 * t + 2];
    assert_close(tot, f[2], 1e-12, 1e-15);
    dem_domain_destroy(d);
}

/* The time-averaged wall force equals the mean of the per-step forces (to rounding: the
 * same sums), its torque follows M_p = M_0 - p x F, and over a settled column it is the
 * weight (momentum balance, 0.1 % as above). */
static void test_mean_wall_force(void **state)
{
    (void)state;
    dem_mesh_wall box;
    dem_material mat;
    int64_t n;
    dem_domain *d = column(&box, &mat, &n, 0.3);
    double f[3], t[3], sec = -1.0;
    assert_ok(dem_mesh_wall_reset_mean_force(d, box));
    assert_ok(dem_mesh_wall_mean_force(d, box, NULL, f, t, &sec));
    assert_true(sec == 0.0 && f[0] == 0.0 && f[1] == 0.0 && f[2] == 0.0); /* no step yet */
    assert_int_equal(dem_mesh_wall_reset_mean_force(d, (dem_mesh_wall){7}), DEM_ERR_UNKNOWN_WALL);
    assert_int_equal(dem_mesh_wall_mean_force(d, (dem_mesh_wall){-1}, NULL, f, t, &sec), DEM_ERR_UNKNOWN_WALL);
    assert_ok(dem_domain_step(d, 20000)); /* falling and settling: a rattling force */
    const double p[3] = {0.003, 0.002, 0.001};
    double fs[3] = {0, 0, 0}, ts[3] = {0, 0, 0};
    const int steps = 300;
    assert_ok(dem_mesh_wall_reset_mean_force(d, box));
    for (int s = 0; s < steps; s++) {
        assert_ok(dem_domain_step(d, 1));
        assert_ok(dem_mesh_wall_force(d, box, p, f, t));
        for (int a = 0; a < 3; a++) {
            fs[a] += f[a] / steps;
            ts[a] += t[a] / steps;
        }
    }
    assert_ok(dem_mesh_wall_mean_force(d, box, p, f, t, &sec));
    assert_close(sec, steps * 5e-6, 1e-12, 0);
    for (int a = 0; a < 3; a++) {
        assert_close(f[a], fs[a], 1e-9, 1e-12 * fabs(fs[2]));
        assert_close(t[a], ts[a], 1e-9, 1e-12 * fabs(fs[2]) * L);
    }
    assert_ok(dem_domain_step(d, 20000)); /* settled */
    assert_ok(dem_mesh_wall_reset_mean_force(d, box));
    assert_ok(dem_domain_step(d, 2000));
    assert_ok(dem_mesh_wall_mean_force(d, box, NULL, f, NULL, NULL));
    assert_close(-f[2], total_weight(d, n), 1e-3, 0);
    dem_domain_destroy(d);
}

/* The plane-wall time average: the mean of the per-step forces (to rounding: the same sums)
 * while the column falls onto a plane floor, then the column's weight, on the floor and by
 * friction on the four plane sides, once it rests (0.1 %, as the mesh box: the residual is the
 * bed's remaining momentum change). */
static void test_plane_wall_mean_force(void **state)
{
    (void)state;
    dem_plane_wall floor_wall;
    dem_material mat;
    dem_plane_wall side[4];
    dem_domain *d = column_domain(&mat);
    dem_plane_wall_def w = dem_default_plane_wall_def(); /* floor z >= 0 */
    w.material = mat;
    assert_ok(dem_plane_wall_add(d, &w, &floor_wall));
    for (int k = 0; k < 4; k++) { /* the four sides of an L x L column */
        w.axis = k / 2;
        w.side = k % 2 ? -1 : 1;
        w.position = k % 2 ? L : 0.0;
        assert_ok(dem_plane_wall_add(d, &w, &side[k]));
    }
    double pos[3 * 100], rad[100];
    dem_material mats[100];
    int64_t n = 0;
    uint64_t rng = 11;
    for (int z = 0; z < 4; z++)
        for (int y = 0; y < 5; y++)
            for (int x = 0; x < 5; x++, n++) {
                pos[3 * n] = 0.0007 + 1.15e-3 * x + 5e-5 * (test_urand(&rng) - 0.5);
                pos[3 * n + 1] = 0.0007 + 1.15e-3 * y + 5e-5 * (test_urand(&rng) - 0.5);
                pos[3 * n + 2] = 0.0008 + 1.15e-3 * z;
                rad[n] = R * (0.9 + 0.1 * test_urand(&rng));
                mats[n] = mat;
            }
    assert_ok(dem_particles_add(d, n, pos, rad, mats, NULL, NULL, NULL));
    double f[3], sec = -1.0, fs[3] = {0, 0, 0};
    assert_ok(dem_plane_wall_reset_mean_force(d, floor_wall));
    assert_ok(dem_plane_wall_mean_force(d, floor_wall, f, &sec));
    assert_true(sec == 0.0 && f[0] == 0.0 && f[1] == 0.0 && f[2] == 0.0); /* no step yet */
    assert_int_equal(dem_plane_wall_reset_mean_force(d, (dem_plane_wall){9}), DEM_ERR_UNKNOWN_WALL);
    assert_int_equal(dem_plane_wall_mean_force(d, (dem_plane_wall){-1}, f, &sec), DEM_ERR_UNKNOWN_WALL);
    const int steps = 3000; /* falling and landing: a rattling force */
    for (int s = 0; s < steps; s++) {
        assert_ok(dem_domain_step(d, 1));
        assert_ok(dem_plane_wall_force(d, floor_wall, f));
        for (int a = 0; a < 3; a++) fs[a] += f[a] / steps;
    }
    assert_ok(dem_plane_wall_mean_force(d, floor_wall, f, &sec));
    assert_close(sec, steps * 5e-6, 1e-12, 0);
    assert_true(fs[2] < 0.0); /* the particles have landed: they push the floor down */
    for (int a = 0; a < 3; a++) assert_close(f[a], fs[a], 1e-9, 1e-12 * fabs(fs[2]));
    assert_ok(dem_domain_step(d, 40000)); /* settled */
    assert_ok(dem_plane_wall_reset_mean_force(d, floor_wall));
    for (int k = 0; k < 4; k++) assert_ok(dem_plane_wall_reset_mean_force(d, side[k]));
    assert_ok(dem_domain_step(d, 2000));
    assert_ok(dem_plane_wall_mean_force(d, floor_wall, f, NULL));
    double down = -f[2]; /* the floor and, by friction, the sides carry the weight */
    for (int k = 0; k < 4; k++) {
        assert_ok(dem_plane_wall_mean_force(d, side[k], f, NULL));
        down -= f[2];
    }
    assert_close(down, total_weight(d, n), 1e-3, 0);
    dem_domain_destroy(d);
}

static void test_servo_lid_and_region_stress(void **state)
{
    (void)state;
    dem_mesh_wall box;
    dem_material mat;
    int64_t n;
    dem_domain *d = column(&box, &mat, &n, 0.0); /* frictionless sides: no Janssen arching */
    assert_ok(dem_domain_step(d, 30000));
    /* lid: a square over the whole box, just above the highest particle */
    double x[3 * 200], zmax = 0.0;
    assert_ok(dem_particles_get_positions(d, x, dem_particle_count(d)));
    for (int64_t i = 0; i < n; i++) zmax = fmax(zmax, x[3 * i + 2]);
    dem_mesh_wall lid = add_grid_mesh(d, 0, L, 0, L, zmax + R + 2e-4, 2, 2, mat);
    const double sigma = 2000.0, area = L * L; /* 72 mN, ~30 x the column's weight */
    dem_servo_def sd = dem_default_servo_def();
    sd.target_stress = sigma;
    sd.area = area;
    sd.max_speed = 0.02;
    assert_ok(dem_mesh_wall_set_servo(d, lid, &sd));
    assert_ok(dem_domain_step(d, 20000)); /* 0.1 s to approach and settle */
    double smin = INFINITY, smax = -INFINITY, fsum = 0.0;
    const int samples = 100;
    for (int s = 0; s < samples; s++) {
        assert_ok(dem_domain_step(d, 100));
        double sn, tau;
        assert_ok(dem_mesh_wall_stress(d, lid, (double[]){0, 0, 1}, area, &sn, &tau));
        smin = fmin(smin, sn);
        smax = fmax(smax, sn);
        fsum += sn;
    }
    /* particles push the lid up: +z stress equals the target, steadily */
    assert_close(fsum / samples, sigma, 0.03, 0);
    assert_close(smin, sigma, 0.05, 0);
    assert_close(smax, sigma, 0.05, 0);

    /* Love–Weber sigma_zz of everything under the lid vs the lid stress: the particles fill
     * the region, so this is the volume average of sigma_zz. Summing the branch vectors
     * particle by particle, the internal contacts cancel and, at any instant,
     * sigma^c_zz V = F_lid z_lid + sum_i z_i f_i,z (f_i: the particle's contact force; floor at
     * z = 0, frictionless sides). At rest f_i,z = m_i g: the lid stress plus the weight's
     * share (~1.7 % here). */
    double tr[3];
    assert_ok(dem_mesh_wall_get_pose(d, lid, tr, NULL));
    dem_region g = dem_default_region();
    g.lo[0] = g.lo[1] = g.lo[2] = 0.0;
    g.hi[0] = g.hi[1] = L;
    g.hi[2] = zmax + R + 2e-4 + tr[2];
    dem_stress st;
    assert_ok(dem_region_stress(d, &g, &st));
    double sn, tau;
    assert_ok(dem_mesh_wall_stress(d, lid, (double[]){0, 0, 1}, area, &sn, &tau));
    assert_int_equal(st.particle_count, n);
    assert_close(st.total[8], sn, 0.05, 0);
    double rad[200], f[3 * 200], zf = 0.0, mgz = 0.0;
    assert_ok(dem_particles_get_positions(d, x, dem_particle_count(d)));
    assert_ok(dem_particles_get_radii(d, rad, dem_particle_count(d)));
    assert_ok(dem_particles_get_forces(d, f, dem_particle_count(d)));
    for (int64_t i = 0; i < n; i++) {
        zf += x[3 * i + 2] * f[3 * i + 2];
        mgz += 2500.0 * 4.0 / 3.0 * M_PI * pow(rad[i], 3) * 9.81 * x[3 * i + 2];
    }
    /* an identity of the sums: round-off only (measured 1e-15 relative); tolerance 1e-12 */
    assert_close(st.contact[8] * st.volume, sn * area * g.hi[2] + zf, 1e-12, 0);
    /* and the bed is at rest: the inertial part sum z (f - m g) measured 1.7e-6 of sigma V
     * (the weight's share is 1.7e-2); tolerance 1e-4 */
    assert_true(fabs(zf - mgz) < 1e-4 * st.contact[8] * st.volume);
    assert_true(st.kinetic[8] < 1e-3 * st.total[8]);
    dem_domain_destroy(d);
}

/* One sphere resting on a plane floor: sigma_zz = F z / V exactly (the only contact, acting
 * at the floor, a lever z below the centre), no other component; a cylinder around it gives the same
 * over its own volume. */
static void test_single_sphere_closed_form(void **state)
{
    (void)state;
    dem_material mat;
    dem_domain *d = make_domain(0.01, 1e-6, 5e6, 0.5, 0.5, &mat);
    double g3[3] = {0, 0, -9.81};
    assert_ok(dem_domain_set_gravity(d, g3));
    add_sphere_over_floor(d, mat, 0.005, R, 1e-7, 0.0);
    assert_ok(dem_domain_step(d, 100000));
    double x[3], f[3];
    assert_ok(dem_particles_get_positions(d, x, dem_particle_count(d)));
    assert_ok(dem_particles_get_forces(d, f, dem_particle_count(d)));
    double lever = x[2]; /* wall contacts act at the wall surface */
    dem_region box = dem_default_region();
    for (int a = 0; a < 3; a++) {
        box.lo[a] = 0.0;
        box.hi[a] = 0.01;
    }
    dem_stress st;
    assert_ok(dem_region_stress(d, &box, &st));
    assert_close(st.contact[8], f[2] * lever / 1e-6, 1e-12, 0);
    assert_close(f[2], 2500.0 * 4.0 / 3.0 * M_PI * R * R * R * 9.81, 1e-6, 0); /* at rest: contact = weight */
    assert_close(st.contact[0], 0.0, 0, 1e-9 * st.contact[8]);
    dem_region cyl = dem_default_region();
    cyl.kind = DEM_REGION_ANNULAR_SECTOR;
    cyl.centre[0] = cyl.centre[1] = 0.005;
    cyl.r_inner = 0.0;
    cyl.r_outer = 0.001;
    cyl.h_lo = 0.0;
    cyl.h_hi = 0.002;
    dem_stress sc;
    assert_ok(dem_region_stress(d, &cyl, &sc));
    assert_close(sc.volume, M_PI * 1e-6 * 0.002, 1e-12, 0);
    assert_close(sc.contact[8] * sc.volume, st.contact[8] * st.volume, 1e-12, 0);
    cyl.angle_lo = 1.0; /* a sector that misses the sphere's centre angle? centre is on the axis: */
    cyl.angle_hi = 2.0; /* atan2(0, 0) = 0 is outside [1, 2] */
    assert_ok(dem_region_stress(d, &cyl, &sc));
    assert_int_equal(sc.particle_count, 0);
    cyl.angle_hi = 0.5;
    assert_int_equal(dem_region_stress(d, &cyl, &sc), DEM_ERR_INVALID_ARGUMENT);
    dem_domain_destroy(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_single_sphere_closed_form),
        cmocka_unit_test(test_column_weight_on_walls),
        cmocka_unit_test(test_mean_wall_force),
        cmocka_unit_test(test_plane_wall_mean_force),
        cmocka_unit_test(test_servo_lid_and_region_stress),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
