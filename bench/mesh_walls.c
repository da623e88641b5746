/* Mesh-wall and output benchmark (issue 3).
 * The packed bed of DESIGN section 10 (20,088 spheres, mu_r 0.1 EPSD2) in three boxes:
 *   plane    five analytic plane walls (the reference)
 *   mesh2    the five faces as one STL-like mesh of 2 triangles per face (10 triangles)
 *   meshfine the five faces finely triangulated (2.2 mm squares: 10,296 triangles)
 * Each settles 20,000 steps (2 threads), then 5,000 steps are timed at 1 and 2 threads,
 * alternating, --repeat times. Then, on the settled plane bed: rendering a 420 x 230 front
 * view and writing an HDF5 snapshot, each timed 10 times (median).
 *
 *   mesh_walls [--settle 20000] [--steps 5000] [--repeat 3] [--csv FILE] [--png FILE] [--h5 FILE] */
#define _POSIX_C_SOURCE 200809L
#include "dem/dem.h"
#include "lattice.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static const double W = 0.040;
static const int NSIDE = 18, NZ = 62;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void check(dem_domain *d, dem_status s, const char *what)
{
    if (s == DEM_OK) return;
    fprintf(stderr, "mesh_walls: %s: %s: %s\n", what, dem_status_name(s), d ? dem_domain_last_error(d) : "");
    exit(1);
}

/* Face k of the open box as an nu x nv grid of squares, appended to V/T. */
static void add_face(int k, int nu, int nv, double H, double *V, int64_t *nvert, int32_t *T, int64_t *ntri)
{
    int64_t base = *nvert;
    for (int j = 0; j <= nv; j++)
        for (int i = 0; i <= nu; i++) {
            double s = (double)i / nu, u = (double)j / nv, *p = V + 3 * (*nvert)++;
            switch (k) {
            case 0: p[0] = s * W; p[1] = u * W; p[2] = 0; break;
            case 1: p[0] = 0; p[1] = s * W; p[2] = u * H; break;
            case 2: p[0] = W; p[1] = s * W; p[2] = u * H; break;
            case 3: p[0] = s * W; p[1] = 0; p[2] = u * H; break;
            default: p[0] = s * W; p[1] = W; p[2] = u * H; break;
            }
        }
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            int32_t a = (int32_t)(base + j * (nu + 1) + i), b = a + 1, c = a + nu + 1, e = c + 1;
            int32_t *q = T + 3 * *ntri;
            q[0] = a; q[1] = b; q[2] = e; q[3] = a; q[4] = e; q[5] = c;
            *ntri += 2;
        }
}

/* variant 0: planes, 1: 2 triangles per face, 2: ~10k triangles */
static dem_domain *build(int variant, int *n_triangles)
{
    dem_domain_def def = dem_default_domain_def();
    def.lo[0] = def.lo[1] = def.lo[2] = 0.0;
    def.hi[0] = def.hi[1] = W;
    def.hi[2] = 1.1e-3 + NZ * LATTICE_SPACING + 0.01;
    def.dt = 1e-5;
    def.skin = 2e-4;
    def.num_threads = 2;
    dem_domain *d;
    char msg[256];
    if (dem_domain_create(&def, &d, msg, sizeof msg) != DEM_OK) {
        fprintf(stderr, "mesh_walls: %s\n", msg);
        exit(1);
    }
    dem_material mat;
    dem_material_def m = dem_default_material_def();
    check(d, dem_material_create(d, &m, &mat), "material");
    dem_pair_def p = dem_default_pair_def();
    p.rolling_friction = 0.1;
    check(d, dem_pair_set(d, mat, mat, &p), "pair");
    *n_triangles = 0;
    if (variant == 0) {
        const int faces[5][2] = {{0, 1}, {0, -1}, {1, 1}, {1, -1}, {2, 1}};
        for (int k = 0; k < 5; k++) {
            dem_plane_wall_def w = dem_default_plane_wall_def();
            w.axis = faces[k][0];
            w.side = faces[k][1];
            w.position = w.side > 0 ? 0.0 : def.hi[w.axis];
            w.material = mat;
            dem_plane_wall id;
            check(d, dem_plane_wall_add(d, &w, &id), "plane wall");
        }
    } else {
        const double H = def.hi[2];
        int nu = variant == 1 ? 1 : 18, nv_side = variant == 1 ? 1 : 67;
        double *V = malloc(sizeof(double) * 3 * 5 * (nu + 1) * (nv_side + 1));
        int32_t *T = malloc(sizeof(int32_t) * 3 * 2 * 5 * nu * nv_side);
        int64_t nvert = 0, ntri = 0;
        for (int k = 0; k < 5; k++) add_face(k, nu, k == 0 ? nu : nv_side, H, V, &nvert, T, &ntri);
        dem_mesh_def md = dem_default_mesh_def();
        md.material = mat;
        dem_mesh_wall id;
        check(d, dem_mesh_wall_add(d, nvert, V, ntri, T, &md, &id), "mesh wall");
        *n_triangles = (int)ntri;
        free(V);
        free(T);
    }
    double *pos, *vel, *rad;
    dem_material *mats;
    const int64_t n = lattice(NSIDE, NZ, mat, &pos, &vel, &rad, &mats);
    check(d, dem_particles_add(d, n, pos, rad, mats, vel, NULL, NULL), "particles");
    free(pos);
    free(vel);
    free(rad);
    free(mats);
    return d;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    int settle = 20000, steps = 5000, repeat = 3;
    const char *csv = NULL, *png = "/tmp/mesh_walls_front.png", *h5 = "/tmp/mesh_walls_snapshot.h5";
    for (int k = 1; k < argc; k++) {
        if (!strcmp(argv[k], "--settle") && k + 1 < argc) settle = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--steps") && k + 1 < argc) steps = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--repeat") && k + 1 < argc) repeat = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--csv") && k + 1 < argc) csv = argv[++k];
        else if (!strcmp(argv[k], "--png") && k + 1 < argc) png = argv[++k];
        else if (!strcmp(argv[k], "--h5") && k + 1 < argc) h5 = argv[++k];
        else {
            fprintf(stderr, "usage: mesh_walls [--settle S] [--steps S] [--repeat R] [--csv FILE] [--png FILE] [--h5 FILE]\n");
            return 2;
        }
    }
    const char *names[3] = {"plane", "mesh2", "meshfine"};
    dem_domain *d[3];
    int ntri[3];
    for (int v = 0; v < 3; v++) {
        d[v] = build(v, &ntri[v]);
        double t0 = now_s();
        check(d[v], dem_domain_step(d[v], settle), "settle");
        printf("%-8s %5d triangles: settled in %.1f s (2 threads)\n", names[v], ntri[v], now_s() - t0);
        fflush(stdout);
    }
    const int64_t n = dem_particle_count(d[0]);
    FILE *out = csv ? fopen(csv, "w") : NULL;
    if (out) fprintf(out, "walls,triangles,threads,run,mpart_steps_per_s,seconds,wall_contacts,frac_neighbor\n");
    double rate[3][2][16];
    for (int r = 0; r < repeat && r < 16; r++)
        for (int th = 1; th <= 2; th++)
            for (int v = 0; v < 3; v++) { /* interleaved so the VM's speed drift hits all alike */
                check(d[v], dem_domain_set_num_threads(d[v], th), "threads");
                check(d[v], dem_domain_profile_reset(d[v]), "profile");
                double t0 = now_s();
                check(d[v], dem_domain_step(d[v], steps), "timed run");
                double el = now_s() - t0;
                dem_profile pr;
                dem_diagnostics g;
                dem_domain_profile(d[v], &pr);
                dem_domain_diagnostics(d[v], &g);
                rate[v][th - 1][r] = (double)n * steps / el / 1e6;
                printf("%-8s threads=%d run %d: %.3f M particle-steps/s (%.2f s), wall contacts %lld, neighbour %.1f%%\n",
                       names[v], th, r, rate[v][th - 1][r], el, (long long)g.wall_contact_count, 100 * pr.neighbor_s / el);
                fflush(stdout);
                if (out)
                    fprintf(out, "%s,%d,%d,%d,%.4f,%.3f,%lld,%.3f\n", names[v], ntri[v], th, r, rate[v][th - 1][r], el,
                            (long long)g.wall_contact_count, pr.neighbor_s / el);
            }
    for (int th = 1; th <= 2; th++)
        for (int v = 0; v < 3; v++) {
            qsort(rate[v][th - 1], (size_t)repeat, sizeof(double), cmp_double);
            double med = rate[v][th - 1][repeat / 2], ref = rate[0][th - 1][repeat / 2];
            printf("median %-8s threads=%d: %.3f M particle-steps/s, time ratio to planes %.3f\n", names[v], th, med, ref / med);
        }

    /* output on the settled plane bed */
    dem_render_def rd = dem_default_render_def(); /* 420 x 230 front view */
    rd.lo[0] = -0.05;
    rd.hi[0] = 0.09;
    rd.lo[1] = 0.0;
    rd.hi[1] = 0.14 * 230.0 / 420.0;
    double tr[10], tw[10];
    unsigned char *rgb = malloc(420 * 230 * 3);
    for (int k = 0; k < 10; k++) {
        double t0 = now_s();
        check(d[1], dem_render_rgb(d[1], &rd, rgb), "render");
        tr[k] = now_s() - t0;
        t0 = now_s();
        check(d[0], dem_snapshot_write(d[0], h5), "snapshot");
        tw[k] = now_s() - t0;
    }
    check(d[1], dem_render_png(d[1], &rd, png), "png");
    qsort(tr, 10, sizeof(double), cmp_double);
    qsort(tw, 10, sizeof(double), cmp_double);
    FILE *fh = fopen(h5, "rb");
    long bytes = 0;
    if (fh) {
        fseek(fh, 0, SEEK_END);
        bytes = ftell(fh);
        fclose(fh);
    }
    printf("render %lld spheres at 420x230: median %.1f ms (min %.1f); PNG in %s\n", (long long)n, 1e3 * tr[5], 1e3 * tr[0], png);
    printf("HDF5 snapshot of %lld spheres (%.1f MB): median %.1f ms (min %.1f)\n", (long long)n, bytes / 1e6, 1e3 * tw[5],
           1e3 * tw[0]);
    if (out) {
        fprintf(out, "render_420x230_ms,,,,%.2f,,,\n", 1e3 * tr[5]);
        fprintf(out, "snapshot_write_ms,,,,%.2f,,,\n", 1e3 * tw[5]);
        fclose(out);
    }
    free(rgb);
    for (int v = 0; v < 3; v++) dem_domain_destroy(d[v]);
    return 0;
}
