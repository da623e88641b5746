/* Packed-bed throughput benchmark (DESIGN section 10).
 * Monodisperse spheres d = 2 mm, rho = 2500 kg/m^3, E = 5 MPa, nu = 0.25, e = 0.5, mu_s = 0.5,
 * mu_r = 0 or 0.1 (EPSD2); frictional plane walls x, y at 0 and W, floor z = 0; simple-cubic
 * lattice of spacing 2.2 mm starting 1.1 mm from the walls, n x n x 62 spheres (18 -> 20,088,
 * W = 40 mm; 40 -> 99,200, W = 88 mm); random initial velocities in +-0.05 m/s; g = 9.81;
 * dt = 1e-5 s; skin 0.2 mm. Settle, then time a number of steps at each thread count.
 *
 *   packed_bed [--n-side 18] [--mu-r 0.1] [--cohesion 0] [--settle 20000] [--steps 5000] [--threads 1,2] [--repeat 1]
 *              [--settle-threads 2] [--csv FILE] [--demo] [--save FILE] [--load FILE]
 * Prints one line per timed run (each thread count, --repeat times over); --csv appends
 * them as CSV rows. --save writes the settled
 * positions and velocities (raw doubles) and --load starts from them instead of the lattice
 * (contact springs start empty, so give --settle a few hundred steps after --load); this is
 * for quick profiling, the committed results settle from the lattice. */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE /* syscall() */
#include "dem/dem.h"
#include "lattice.h"
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#ifdef __linux__
#include <linux/perf_event.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

/* A hardware counter of the calling thread (user space): PERF_COUNT_HW_CPU_CYCLES or
 * _INSTRUCTIONS; -1 where the machine or its settings offer none. Why cycles: the VMs this
 * runs on change speed by +-15 % over minutes (and a session's machine type is not always the
 * same), so particle-steps per second alone cannot compare runs of different hours; cycles
 * per particle-step can. Why instructions: the work per particle-step, whatever the caches do
 * (constant over bed sizes = cost linear in N). Counted for the main thread only, so
 * meaningful for 1-thread runs. */
static int counter_open(unsigned long long config)
{
#ifdef __linux__
    struct perf_event_attr a;
    memset(&a, 0, sizeof a);
    a.type = PERF_TYPE_HARDWARE;
    a.size = sizeof a;
    a.config = config;
    a.exclude_kernel = 1;
    a.exclude_hv = 1;
    return (int)syscall(SYS_perf_event_open, &a, 0, -1, -1, 0);
#else
    (void)config;
    return -1;
#endif
}

static double counter_read(int fd)
{
#ifdef __linux__
    uint64_t v;
    if (fd >= 0 && read(fd, &v, sizeof v) == (ssize_t)sizeof v) return (double)v;
#else
    (void)fd;
#endif
    return -1.0;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Peak resident memory of the process (kB), from /proc. */
static long peak_rss_kb(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    long kb = -1;
    if (!f) return -1;
    while (fgets(line, sizeof line, f))
        if (strncmp(line, "VmHWM:", 6) == 0) kb = strtol(line + 6, NULL, 10);
    fclose(f);
    return kb;
}

/* Contacts per particle: a pair contact counts for both spheres, a wall contact for one. */
static double contacts_per_particle(const dem_diagnostics *g, int64_t n)
{
    return (2.0 * (double)(g->contact_count - g->wall_contact_count) + (double)g->wall_contact_count) / (double)n;
}

static void die(dem_domain *d, dem_status s, const char *what)
{
    fprintf(stderr, "packed_bed: %s: %s: %s\n", what, dem_status_name(s), d ? dem_domain_last_error(d) : "");
    exit(1);
}

/* The box: material, pair constants, five frictional plane walls (open top). */
static dem_domain *build_domain(const dem_domain_def *def, double mu_r, double cohesion, dem_material *mat)
{
    dem_domain *d;
    char msg[256];
    dem_status s = dem_domain_create(def, &d, msg, sizeof msg);
    if (s != DEM_OK) {
        fprintf(stderr, "packed_bed: %s\n", msg);
        exit(1);
    }
    dem_material_def m = dem_default_material_def(); /* E 5 MPa, nu 0.25, rho 2500 */
    if ((s = dem_material_create(d, &m, mat)) != DEM_OK) die(d, s, "material");
    dem_pair_def p = dem_default_pair_def();          /* e 0.5, mu_s 0.5, EPSD2 */
    p.rolling_friction = mu_r;
    if ((s = dem_pair_set(d, *mat, *mat, &p)) != DEM_OK) die(d, s, "pair");
    if (cohesion > 0.0 && (s = dem_pair_set_effect(d, *mat, *mat, "cohesion_sjkr", &cohesion, 1)) != DEM_OK)
        die(d, s, "cohesion");
    const int faces[5][2] = {{0, 1}, {0, -1}, {1, 1}, {1, -1}, {2, 1}};
    for (int k = 0; k < 5; k++) {
        dem_plane_wall_def w = dem_default_plane_wall_def();
        w.axis = faces[k][0];
        w.side = faces[k][1];
        w.position = w.side > 0 ? 0.0 : def->hi[w.axis];
        w.material = *mat;
        dem_plane_wall id;
        if ((s = dem_plane_wall_add(d, &w, &id)) != DEM_OK) die(d, s, "wall");
    }
    return d;
}

int main(int argc, char **argv)
{
    int n_side = 18, settle = 20000, steps = 5000, settle_threads = 2, demo = 0, repeat = 1;
    double mu_r = 0.1, cohesion = 0.0;
    const char *threads_arg = "1,2", *csv = NULL, *save = NULL, *load = NULL;
    for (int k = 1; k < argc; k++) {
        if (!strcmp(argv[k], "--n-side") && k + 1 < argc) n_side = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--mu-r") && k + 1 < argc) mu_r = atof(argv[++k]);
        else if (!strcmp(argv[k], "--cohesion") && k + 1 < argc) cohesion = atof(argv[++k]);
        else if (!strcmp(argv[k], "--settle") && k + 1 < argc) settle = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--steps") && k + 1 < argc) steps = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--repeat") && k + 1 < argc) repeat = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--threads") && k + 1 < argc) threads_arg = argv[++k];
        else if (!strcmp(argv[k], "--settle-threads") && k + 1 < argc) settle_threads = atoi(argv[++k]);
        else if (!strcmp(argv[k], "--csv") && k + 1 < argc) csv = argv[++k];
        else if (!strcmp(argv[k], "--demo")) demo = 1;
        else if (!strcmp(argv[k], "--save") && k + 1 < argc) save = argv[++k];
        else if (!strcmp(argv[k], "--load") && k + 1 < argc) load = argv[++k];
        else {
            fprintf(stderr, "usage: packed_bed [--n-side N] [--mu-r X] [--cohesion J_PER_M3] [--settle S] [--steps S] [--threads 1,2] [--repeat R] "
                            "[--settle-threads T] [--csv FILE] [--demo]\n");
            return 2;
        }
    }
    const int nz = 62;
    const double spacing = LATTICE_SPACING;
    dem_status s;
    dem_domain_def def = dem_default_domain_def();
    def.lo[0] = def.lo[1] = def.lo[2] = 0.0;
    def.hi[0] = def.hi[1] = n_side == 18 ? 0.040 : n_side * spacing; /* 40 mm and 88 mm as in DESIGN */
    def.hi[2] = 1.1e-3 + nz * spacing + 0.01;
    def.dt = 1e-5;
    def.skin = 2e-4;
    def.num_threads = settle_threads;
    if (load) def.insert_overlap_ratio = 0.2; /* settled spheres touch: accept their overlaps */
    dem_material mat;
    dem_domain *d = build_domain(&def, mu_r, cohesion, &mat);
    double *pos, *vel, *rad;
    dem_material *mats;
    const int64_t n = lattice(n_side, nz, mat, &pos, &vel, &rad, &mats);
    double *angvel = calloc((size_t)(3 * n), sizeof(double));
    if (load) {
        FILE *f = fopen(load, "rb");
        if (!f || fread(pos, sizeof(double), (size_t)(3 * n), f) != (size_t)(3 * n) ||
            fread(vel, sizeof(double), (size_t)(3 * n), f) != (size_t)(3 * n) ||
            fread(angvel, sizeof(double), (size_t)(3 * n), f) != (size_t)(3 * n)) {
            fprintf(stderr, "packed_bed: cannot read %lld particles from %s\n", (long long)n, load);
            return 1;
        }
        fclose(f);
    }
    if ((s = dem_particles_add(d, n, pos, rad, mats, vel, angvel, NULL)) != DEM_OK) die(d, s, "particles");
    free(pos);
    free(vel);
    free(angvel);
    free(rad);
    free(mats);

    if (demo)
        printf("libdem %s: settling a packed bed of %lld glass-like spheres (d = 2 mm, E = 5 MPa, e = 0.5, "
               "mu_s = 0.5, mu_r = %.2f EPSD2) in a %.0f mm box, %d steps of 10 us on %d threads\n",
               dem_version_string(), (long long)n, mu_r, 1e3 * def.hi[0], settle, settle_threads);
    /* settle */
    double t0 = now_s();
    const int chunk = 1000;
    for (int done = 0; done < settle; done += chunk) {
        int c = settle - done < chunk ? settle - done : chunk;
        if ((s = dem_domain_step(d, c)) != DEM_OK) die(d, s, "settle");
        if (demo) {
            dem_diagnostics g;
            dem_domain_diagnostics(d, &g);
            printf("  t = %.3f s  kinetic energy %.3e J  contacts/particle %.2f  max overlap %.3f R  (%.1f s)\n",
                   g.time, g.kinetic_energy, contacts_per_particle(&g, n), g.max_overlap_ratio,
                   now_s() - t0);
            fflush(stdout);
        }
    }
    double settle_s = now_s() - t0;
    if (save) {
        double *buf = malloc(sizeof(double) * 3 * n);
        FILE *f = fopen(save, "wb");
        dem_particles_get_positions(d, buf, dem_particle_count(d));
        fwrite(buf, sizeof(double), (size_t)(3 * n), f);
        dem_particles_get_velocities(d, buf, dem_particle_count(d));
        fwrite(buf, sizeof(double), (size_t)(3 * n), f);
        dem_particles_get_angular_velocities(d, buf, dem_particle_count(d));
        fwrite(buf, sizeof(double), (size_t)(3 * n), f);
        fclose(f);
        free(buf);
    }
    if (demo) {
        dem_profile pr;
        dem_domain_profile(d, &pr);
        printf("settled %lld spheres (mu_r = %.2f) for %d steps in %.1f s on %d threads: %.2f M particle-steps/s\n",
               (long long)n, mu_r, settle, settle_s, settle_threads, (double)n * settle / settle_s / 1e6);
        dem_domain_destroy(d);
        return 0;
    }

    FILE *out = csv ? fopen(csv, "a") : NULL;
    if (csv && !out) {
        fprintf(stderr, "packed_bed: cannot open %s for appending\n", csv);
        dem_domain_destroy(d);
        return 1;
    }
    if (out && ftell(out) == 0) /* a new file: the header first */
        fprintf(out, "particles,mu_r,threads,steps,mpart_steps_per_s,seconds,contacts_per_particle,frac_neighbor,"
                     "frac_force_sweep,frac_integration_est,neighbor_builds,libdem_bytes_per_particle,peak_rss_mib,"
                     "settle_seconds,cycles_per_particle_step,clock_ghz,instructions_per_particle_step\n");
    char list[64];
    snprintf(list, sizeof list, "%s", threads_arg);
    int thread_counts[16], n_counts = 0;
    for (char *tok = strtok(list, ","); tok && n_counts < 16; tok = strtok(NULL, ",")) thread_counts[n_counts++] = atoi(tok);
    const int cycles_fd = counter_open(PERF_COUNT_HW_CPU_CYCLES), instr_fd = counter_open(PERF_COUNT_HW_INSTRUCTIONS);
    for (int run = 0; run < repeat * n_counts; run++) {
        int nt = thread_counts[run % n_counts];
        dem_domain_set_num_threads(d, nt);
        dem_domain_profile_reset(d);
        const double c1 = counter_read(cycles_fd), i1 = counter_read(instr_fd);
        double t1 = now_s();
        if ((s = dem_domain_step(d, steps)) != DEM_OK) die(d, s, "timed run");
        double el = now_s() - t1;
        const double c2 = counter_read(cycles_fd), i2 = counter_read(instr_fd);
        /* cycles and instructions per particle-step, the clock they ran at (1 thread, where
         * counted) */
        const double cps = nt == 1 && c1 >= 0 && c2 >= 0 ? (c2 - c1) / ((double)n * steps) : -1.0;
        const double ips = nt == 1 && i1 >= 0 && i2 >= 0 ? (i2 - i1) / ((double)n * steps) : -1.0;
        const double ghz = cps > 0 ? (c2 - c1) / el / 1e9 : -1.0;
        dem_profile pr;
        dem_diagnostics g;
        dem_domain_diagnostics(d, &g);
        /* the integration share: a one-step call runs the opening kick + drift as a separate
         * pass (integrate_s); its time per pass estimates the integration inside the sweep */
        dem_domain_profile(d, &pr);
        dem_profile one;
        dem_domain_profile_reset(d);
        for (int k = 0; k < 100; k++)
            if ((s = dem_domain_step(d, 1)) != DEM_OK) die(d, s, "single steps");
        dem_domain_profile(d, &one);
        double integ_frac = (one.integrate_s / 100.0) / (el / steps);
        double rate = (double)n * steps / el;
        double cpp = contacts_per_particle(&g, n);
        double mem_pp = (double)dem_domain_memory_bytes(d) / (double)n;
        long rss = peak_rss_kb();
        printf("N=%lld mu_r=%.2f threads=%d: %.3f M particle-steps/s  (%.2f s for %d steps)  contacts/particle %.2f  "
               "split: neighbour %.1f%% force sweep %.1f%% (of which integration ~%.1f%%)  builds %lld  list entries/particle %.2f  "
               "libdem memory %.0f B/particle  peak RSS %.1f MiB (%.0f B/particle)",
               (long long)n, mu_r, nt, rate / 1e6, el, steps, cpp, 100 * pr.neighbor_s / el,
               100 * (pr.contact_s + pr.integrate_s) / el, 100 * integ_frac, (long long)pr.neighbor_builds, (double)pr.neighbor_pairs / (double)n, mem_pp,
               rss / 1024.0,
               rss * 1024.0 / (double)n);
        if (cps > 0) printf("  %.0f cycles/particle-step at %.2f GHz", cps, ghz);
        if (ips > 0) printf("  %.0f instructions/particle-step", ips);
        printf("\n");
        char cyc[64] = ",", ins[32] = "";
        if (cps > 0) snprintf(cyc, sizeof cyc, "%.1f,%.3f", cps, ghz);
        if (ips > 0) snprintf(ins, sizeof ins, "%.1f", ips);
        if (out)
            fprintf(out, "%lld,%.2f,%d,%d,%.4f,%.3f,%.2f,%.3f,%.3f,%.3f,%lld,%.0f,%.1f,%.1f,%s,%s\n", (long long)n, mu_r, nt,
                    steps, rate / 1e6, el, cpp, pr.neighbor_s / el, (pr.contact_s + pr.integrate_s) / el, integ_frac,
                    (long long)pr.neighbor_builds, mem_pp, rss / 1024.0, settle_s, cyc, ins);
        fflush(stdout);
    }
    if (out) fclose(out);
#ifdef __linux__
    if (cycles_fd >= 0) close(cycles_fd);
    if (instr_fd >= 0) close(instr_fd);
#endif
    dem_domain_destroy(d);
    return 0;
}
