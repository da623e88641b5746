/* Mesh walls against the analytic plane (already verified against Hertz in test_hertz):
 * a flat mesh must be indistinguishable from the plane wherever the sphere touches it (face,
 * edge, vertex shared by six triangles), friction history must cross seams, a moving
 * mesh must carry its surface velocity into the contacts (belt closed form), and the mesh
 * candidate lists never miss a contact, for a still mesh and for a moving one (whose cell
 * bins are remade only after it moved a margin). */
#include "mesh_util.h"

static const double R = 1e-3, E = 1e7;

typedef struct drop { double peak_force, contact_time, rebound; int max_contacts; } drop;

/* Sphere of radius R dropped at (x, y) from just above z = 0 at 0.5 m/s, onto a plane
 * (mesh_n = 0) or a grid mesh of mesh_n x mesh_n squares over [0, 0.01]^2. */
static drop run_drop(int mesh_n, double x, double y, double e, double mu)
{
    dem_material mat;
    dem_domain *d = make_domain(0.01, 2e-7, E, e, mu, &mat);
    assert_non_null(d);
    if (mesh_n == 0) {
        dem_plane_wall w;
        dem_plane_wall_def pw = dem_default_plane_wall_def();
        pw.material = mat;
        assert_ok(dem_plane_wall_add(d, &pw, &w));
    } else {
        add_grid_mesh(d, 0, 0.01, 0, 0.01, 0, mesh_n, mesh_n, mat);
    }
    double pos[3] = {x, y, R + 1e-6}, vel[3] = {0.1, 0.05, -0.5}; /* oblique: friction acts too */
    assert_ok(dem_particles_add(d, 1, pos, (double[]){R}, &mat, vel, NULL, NULL));
    drop r = {0, 0, 0, 0};
    int touching = 0;
    for (int s = 0; s < 400000; s++) {
        assert_ok(dem_domain_step(d, 1));
        double f[3], v3[3];
        dem_diagnostics dg;
        assert_ok(dem_particles_get_forces(d, f, dem_particle_count(d)));
        assert_ok(dem_domain_diagnostics(d, &dg));
        if (dg.wall_contact_count > r.max_contacts) r.max_contacts = (int)dg.wall_contact_count;
        if (dg.wall_contact_count > 0) {
            touching = 1;
            r.contact_time += 2e-7;
            if (f[2] > r.peak_force) r.peak_force = f[2];
        } else if (touching) {
            assert_ok(dem_particles_get_velocities(d, v3, dem_particle_count(d)));
            r.rebound = v3[2];
            break;
        }
    }
    dem_domain_destroy(d);
    return r;
}

static void test_flat_mesh_equals_plane(void **state)
{
    (void)state;
    drop plane = run_drop(0, 0.005, 0.005, 0.5, 0.3);
    assert_true(plane.rebound > 0.2);
    /* 4 x 4 squares of 2.5 mm: (5, 5) mm is a vertex of six triangles, (6.25, 5) the middle
     * of an edge, (5.9, 5.3) inside a triangle */
    const double where[3][2] = {{0.0059, 0.0053}, {0.00625, 0.005}, {0.005, 0.005}};
    for (int k = 0; k < 3; k++) {
        drop m = run_drop(4, where[k][0], where[k][1], 0.5, 0.3);
        /* the same contact law on the same geometry: equal to round-off, tolerance 1e-3 as the issue asks */
        assert_close(m.peak_force, plane.peak_force, 1e-3, 0);
        assert_close(m.contact_time, plane.contact_time, 1e-3, 0);
        assert_close(m.rebound, plane.rebound, 1e-3, 0);
        assert_int_equal(m.max_contacts, 1);
    }
}

/* A sphere rolling with rolling resistance across many seams (edges and near-vertices of a
 * fine grid) decelerates exactly as on the plane: the tangential spring and the rolling
 * torque history are carried from triangle to triangle. */
static void roll(int mesh, double out[6], int *max_contacts)
{
    dem_material mat;
    dem_domain *d = make_domain(0.04, 1e-6, E, 0.5, 0.5, &mat);
    assert_non_null(d);
    dem_pair_def p;
    assert_ok(dem_pair_get(d, mat, mat, &p));
    p.rolling_friction = 0.05;
    assert_ok(dem_pair_set(d, mat, mat, &p));
    double g[3] = {0, 0, -9.81};
    assert_ok(dem_domain_set_gravity(d, g));
    if (mesh) {
        add_grid_mesh(d, 0, 0.04, 0, 0.04, 0, 32, 32, mat); /* 1.25 mm squares */
    } else {
        dem_plane_wall w;
        dem_plane_wall_def pw = dem_default_plane_wall_def();
        pw.material = mat;
        assert_ok(dem_plane_wall_add(d, &pw, &w));
    }
    /* resting overlap first, then a push along a direction that crosses edges at all angles */
    double pos[3] = {0.005, 0.006, R - 5e-7}, vel[3] = {0.15, 0.055, 0};
    assert_ok(dem_particles_add(d, 1, pos, (double[]){R}, &mat, vel, NULL, NULL));
    *max_contacts = 0;
    for (int s = 0; s < 60; s++) {
        assert_ok(dem_domain_step(d, 1000));
        dem_diagnostics dg;
        assert_ok(dem_domain_diagnostics(d, &dg));
        if (dg.wall_contact_count > *max_contacts) *max_contacts = (int)dg.wall_contact_count;
    }
    assert_ok(dem_particles_get_positions(d, out, dem_particle_count(d)));
    assert_ok(dem_particles_get_velocities(d, out + 3, dem_particle_count(d)));
    dem_domain_destroy(d);
}

static void test_history_crosses_seams(void **state)
{
    (void)state;
    double a[6], b[6];
    int ca, cb;
    roll(0, a, &ca);
    roll(1, b, &cb);
    assert_int_equal(cb, 1);
    double speed_plane = hypot(a[3], a[4]), speed_mesh = hypot(b[3], b[4]);
    assert_true(speed_plane > 0.01); /* still rolling, decelerated by mu_r */
    /* carried histories reproduce the plane to ~1e-9 (contact points differ by round-off);
     * dropping the history at the seams shifts the position by 2.8e-6 (measured with the
     * hand-over disabled): tolerance 1e-7 separates the two */
    assert_close(speed_mesh, speed_plane, 1e-7, 0);
    assert_close(b[0], a[0], 1e-7, 0);
    assert_close(b[1], a[1], 1e-7, 0);
}

/* Belt: a sphere at rest on a floor that starts moving at u slides, spins up and rolls at
 * v = 2u/7 (Coulomb friction, no rolling resistance): the mesh surface velocity works. */
static void test_moving_mesh_belt(void **state)
{
    (void)state;
    dem_material mat;
    dem_domain *d = make_domain(0.04, 1e-6, E, 0.5, 0.3, &mat);
    assert_non_null(d);
    double g[3] = {0, 0, -9.81};
    assert_ok(dem_domain_set_gravity(d, g));
    dem_mesh_wall m = add_grid_mesh(d, 0.0, 0.04, 0, 0.04, 0, 8, 8, mat);
    double pos[3] = {0.02, 0.02, R - 5e-7};
    assert_ok(dem_particles_add(d, 1, pos, (double[]){R}, &mat, NULL, NULL, NULL));
    assert_ok(dem_domain_step(d, 5000)); /* come to rest */
    const double u = -0.05;
    assert_ok(dem_mesh_wall_set_motion(d, m, (double[]){u, 0, 0}, NULL, NULL));
    assert_ok(dem_domain_step(d, 60000)); /* slip ends after 2u/(7 mu g) = 5 ms */
    double vel[3], pose_t[3];
    assert_ok(dem_particles_get_velocities(d, vel, dem_particle_count(d)));
    assert_ok(dem_mesh_wall_get_pose(d, m, pose_t, NULL));
    assert_close(vel[0], 2.0 * u / 7.0, 1e-3, 0);
    assert_close(pose_t[0], u * 60000 * 1e-6, 1e-9, 0); /* the wall moved u t */
    dem_domain_destroy(d);
}

/* Rotation about an arbitrary axis through a centre: after n steps the vertices are the
 * exact rotation by |w| n dt (Rodrigues), to round-off. */
static void test_rotation_pose(void **state)
{
    (void)state;
    dem_material mat;
    dem_domain *d = make_domain(0.04, 1e-5, E, 0.5, 0.3, &mat);
    dem_mesh_wall m = add_grid_mesh(d, 0.01, 0.03, 0.01, 0.03, 0.02, 2, 2, mat);
    dem_mesh_info info;
    assert_ok(dem_mesh_wall_info(d, m, &info));
    const int64_t nv = info.vertex_count;
    double *v = malloc((size_t)nv * 3 * sizeof(double));
    assert_ok(dem_mesh_wall_get_vertices(d, m, v, nv)); /* before the motion */
    double axis[3] = {1 / sqrt(3.0), 1 / sqrt(3.0), 1 / sqrt(3.0)}, w = 2.0, c[3] = {0.02, 0.02, 0.02};
    double om[3] = {w * axis[0], w * axis[1], w * axis[2]};
    assert_ok(dem_mesh_wall_set_motion(d, m, (double[]){0, 0, 0}, om, c));
    assert_ok(dem_domain_step(d, 1000)); /* no particles: the wall still moves */
    double th = w * 1000 * 1e-5, cs = cos(th), sn = sin(th);
    double *x = malloc((size_t)nv * 3 * sizeof(double));
    assert_ok(dem_mesh_wall_get_vertices(d, m, x, nv));
    double err = 0.0;
    for (int64_t k = 0; k < nv; k++) {
        double p[3] = {v[3 * k] - c[0], v[3 * k + 1] - c[1], v[3 * k + 2] - c[2]}, kxp[3], kp;
        kxp[0] = axis[1] * p[2] - axis[2] * p[1];
        kxp[1] = axis[2] * p[0] - axis[0] * p[2];
        kxp[2] = axis[0] * p[1] - axis[1] * p[0];
        kp = axis[0] * p[0] + axis[1] * p[1] + axis[2] * p[2];
        for (int a = 0; a < 3; a++) {
            double want = c[a] + p[a] * cs + kxp[a] * sn + axis[a] * kp * (1 - cs);
            err = fmax(err, fabs(x[3 * k + a] - want));
        }
    }
    if (getenv("DEM_TEST_VERBOSE")) printf("  rotation error %.3g m\n", err);
    assert_true(err < 1e-12); /* 1000 compositions of a re-orthonormalised rotation */
    free(x);
    free(v);
    dem_domain_destroy(d);
}

/* Spheres between a moving plate and a still lid: at every check the number of sphere-mesh
 * contacts the library sees equals a brute-force count of spheres closer than their radius to
 * either plane (both meshes are flat and wider than the cloud: one contact per touching
 * sphere). Exact integer equality. The plate either rises 18 mm, ~90 times the margin its cell
 * bins are made with, so they are remade many times (the lid's are made once), or swings up
 * about a hinge 7 cm away by 0.18 rad (12-13 mm under the cloud). Both motions also test that a
 * candidate is only skipped while the particle's and the triangle's displacements since the
 * build cannot have closed its gap (mesh_contact.c): a rotation moves no point of a triangle
 * farther than its farthest vertex. */
static void candidates_case(int hinged)
{
    dem_material mat;
    dem_domain *d = make_domain(0.04, 1e-6, E, 0.5, 0.3, &mat);
    assert_non_null(d);
    const double z_plate = 0.001, z_lid = 0.035, u = 0.5, hinge[3] = {-0.05, 0.02, z_plate};
    dem_mesh_wall plate = add_grid_mesh(d, 0.0, 0.04, 0.0, 0.04, z_plate, 8, 8, mat);
    add_grid_mesh(d, 0.0, 0.04, 0.0, 0.04, z_lid, 4, 4, mat);
    enum { N = 48 };
    double pos[3 * N], vel[3 * N], rad[N];
    dem_material mats[N];
    uint64_t rng = 0x2545F4914F6CDD1DULL;
    for (int k = 0; k < N; k++) { /* 4 x 4 x 3 lattice of 3 mm, random velocities up to 0.3 m/s */
        pos[3 * k] = 0.0155 + 3e-3 * (k % 4);
        pos[3 * k + 1] = 0.0155 + 3e-3 * ((k / 4) % 4);
        pos[3 * k + 2] = 0.008 + 3e-3 * (k / 16);
        for (int a = 0; a < 3; a++) vel[3 * k + a] = 0.6 * (test_urand(&rng) - 0.5);
        rad[k] = R;
        mats[k] = mat;
    }
    assert_ok(dem_particles_add(d, N, pos, rad, mats, vel, NULL, NULL));
    if (hinged) /* about +y through the hinge: points at x > -0.05 rise */
        assert_ok(dem_mesh_wall_set_motion(d, plate, (double[]){0, 0, 0}, (double[]){0, -5.0, 0}, hinge));
    else
        assert_ok(dem_mesh_wall_set_motion(d, plate, (double[]){0, 0, u}, NULL, NULL));
    int64_t seen = 0;
    for (int chunk = 0; chunk < 180; chunk++) { /* 36,000 steps */
        assert_ok(dem_domain_step(d, 200));
        double x[3 * N], t[3], rot[9];
        assert_ok(dem_particles_get_positions(d, x, dem_particle_count(d)));
        assert_ok(dem_mesh_wall_get_pose(d, plate, t, rot));
        /* the plate's plane: through R x0 + t of a reference point on it, normal R (0, 0, 1) */
        const double x0[3] = {0.0, 0.0, z_plate}, n[3] = {rot[2], rot[5], rot[8]};
        double on[3];
        for (int a = 0; a < 3; a++) on[a] = rot[3 * a] * x0[0] + rot[3 * a + 1] * x0[1] + rot[3 * a + 2] * x0[2] + t[a];
        int64_t brute = 0;
        for (int k = 0; k < N; k++) {
            const double *p = x + 3 * k;
            double h = (p[0] - on[0]) * n[0] + (p[1] - on[1]) * n[1] + (p[2] - on[2]) * n[2];
            brute += (fabs(h) < R) + (fabs(p[2] - z_lid) < R);
        }
        dem_diagnostics g;
        assert_ok(dem_domain_diagnostics(d, &g));
        assert_int_equal(g.wall_contact_count, brute);
        seen += brute;
    }
    if (getenv("DEM_TEST_VERBOSE")) printf("  %s plate: sphere-mesh contacts seen at the checks: %lld\n",
                                           hinged ? "hinged" : "rising", (long long)seen);
    assert_true(seen > 30); /* contacts did happen */
    dem_domain_destroy(d);
}

static void test_mesh_candidates_find_every_contact(void **state)
{
    (void)state;
    candidates_case(0);
    candidates_case(1);
}

/* dem_domain_memory_bytes counts mesh walls: adding a 20,000-triangle mesh under a resting
 * sphere grows it by at least the triangles' normals and indices (48 bytes each), far more
 * than the sphere's lists can change. */
static void test_memory_counts_meshes(void **state)
{
    (void)state;
    dem_material mat;
    dem_domain *d = make_domain(0.04, 1e-6, E, 0.5, 0.3, &mat);
    assert_non_null(d);
    double pos[3] = {0.02, 0.02, 0.02};
    assert_ok(dem_particles_add(d, 1, pos, (double[]){R}, &mat, NULL, NULL, NULL));
    assert_ok(dem_domain_step(d, 1));
    const size_t before = dem_domain_memory_bytes(d);
    add_grid_mesh(d, 0.0, 0.04, 0.0, 0.04, 0.001, 100, 100, mat);
    assert_ok(dem_domain_step(d, 1));
    const size_t after = dem_domain_memory_bytes(d);
    if (getenv("DEM_TEST_VERBOSE")) printf("  memory %zu -> %zu bytes\n", before, after);
    assert_true(after >= before + 20000 * 48);
    dem_domain_destroy(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_mesh_equals_plane),
        cmocka_unit_test(test_history_crosses_seams),
        cmocka_unit_test(test_moving_mesh_belt),
        cmocka_unit_test(test_rotation_pose),
        cmocka_unit_test(test_mesh_candidates_find_every_contact),
        cmocka_unit_test(test_memory_counts_meshes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
