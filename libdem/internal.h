/* libdem internals: the domain struct and the functions the source files share. */
#ifndef DEM_INTERNAL_H
#define DEM_INTERNAL_H

#include "dem/dem.h"
#include "alloc.h"
#include "thread_governor.h"
#include <math.h>
#include <stdarg.h>

#define DEM_MAX_EFFECTS_PER_PAIR 4
#define DEM_MAX_EFFECT_PARAMS 4
#define DEM_ERRMSG_SIZE 512
#define DEM_PI 3.14159265358979323846

/* One active effect on a material pair. */
typedef struct pair_effect {
    int effect;                          /* index into the effect registry */
    double params[DEM_MAX_EFFECT_PARAMS];
} pair_effect;

/* Derived constants of a material pair, used by the contact law. */
typedef struct pair_props {
    dem_pair_def def;
    double e_star;           /* effective Young's modulus E* */
    double g_star;           /* effective shear modulus G* */
    double damping_factor;   /* gamma = damping_factor * sqrt(S m*), restitution-corrected */
    double st_over_sn_sqrt;  /* sqrt(S_t / S_n) = sqrt(4 G* / E*) */
    int n_effects;
    pair_effect effects[DEM_MAX_EFFECTS_PER_PAIR];
} pair_props;

typedef struct plane_wall {
    dem_plane_wall_def def;
    double normal[3];
    /* time average of the wall force (wall_mean_force.c): the integral since the last reset */
    int averaging;
    double impulse[3], averaged_time;
} plane_wall;

/* A triangle-mesh wall. Vertices are stored as loaded (reference) and as moved (world):
 * x = R x0 + t. Rotation is about the world point `centre`, which moves with the wall. */
typedef struct mesh_wall {
    int material;
    int64_t nv, nt, ne;
    double *x_ref, *x;       /* 3 nv */
    double *x_build;         /* 3 nv: world vertices at the last neighbour build */
    double disp;             /* largest vertex displacement from x_build now (a rigid motion moves
                              * no point of a triangle farther than its farthest vertex) */
    int32_t *tri;            /* 3 nt vertex indices */
    int32_t *tri_edge;       /* 3 nt edge ids: edges (v0 v1), (v1 v2), (v2 v0) */
    int32_t *edge_ntri;      /* ne: triangles sharing the edge */
    double *normal;          /* 3 nt, unit, world */
    int64_t skipped_degenerate, input_triangles;
    /* pose and motion */
    double rot[9], trans[3]; /* R row-major, t */
    double centre[3];        /* rotation centre, world, m */
    double velocity[3], omega[3];
    int moving;              /* any non-zero motion or servo */
    /* cell bins (mesh_bins.c): the triangles within bin_reach of each cell of the grid they
     * were made for, with the vertices at x_binned; valid while the grid and reach are the same
     * and no vertex has moved more than bin_margin from there */
    int32_t *bin_start;      /* n_cells + 1, or NULL before the first binning */
    int32_t *bin_tri;
    int64_t bin_capacity;
    double *x_binned;        /* 3 nv */
    int bin_ncell[3];
    double bin_reach, bin_margin;
    /* load control */
    int servo_on;
    dem_servo_def servo;
    double servo_force;      /* filtered measured force along -direction, N */
    int servo_primed;        /* the filter has seen a first value */
    /* time average of the wall force (wall_mean_force.c): integrals since the last reset */
    int averaging;           /* accumulate every step */
    double impulse[3];       /* sum of F dt, N s */
    double moment_impulse[3];/* sum of (x - 0) x F dt about the origin, N m s */
    double averaged_time;    /* sum of dt, s */
} mesh_wall;

#include "contact_lists.h"

#define DEM_SPLIT_MAX 64 /* threads whose rows the sweep balances (more: an even split) */

struct dem_domain {
    dem_domain_def def;
    char errmsg[DEM_ERRMSG_SIZE];

    /* materials */
    int n_materials, cap_materials;
    dem_material_def *materials;
    pair_props *pairs;        /* n_materials^2, symmetric */

    /* particles, in internal (spatially sorted) order */
    int64_t n, cap;
    double *x, *v, *w;        /* 3n each: position, velocity, angular velocity */
    double *f, *t;            /* 3n: contact force and torque of the last step */
    double *x_build;          /* 3n: positions at the last neighbour build */
    double *radius, *inv_mass, *inv_inertia;
    int32_t *mat;
    dem_particle_id *id;
    dem_particle_id next_id;
    int32_t *index_of_id;     /* next_id entries, -1 if removed */
    int64_t cap_ids;

    /* walls */
    int n_walls, cap_walls;
    plane_wall *walls;

    /* the neighbour build's per-thread scan buffers (neighbor.c), kept between builds */
    void *scan;
    int n_scan;

    /* mesh walls */
    int n_meshes, cap_meshes;
    mesh_wall *meshes;
    double mesh_disp;         /* largest mesh-vertex displacement since the last build, m */
    void *mesh_scratch;       /* mesh_scratch_threads pair batches: each sweep thread's for its
                               * mesh contacts (mesh_contact.c) */
    int mesh_scratch_threads;

    /* neighbour search */
    pair_list pairs_cur, pairs_old;
    wall_list walls_cur, walls_old;
    tri_list tris_cur, tris_old;
    double *slot;             /* 6 per pair entry: contact force on i (the partner gets minus
                               * it), torque on the partner; zero once the pair stops touching.
                               * Current for every entry after the last sweep of a step call
                               * (forces_valid); during a call only for entries whose partner is
                               * finished from its slots (deferred, sweep.c) */
    int64_t *trans_start;     /* n + 1: entries where particle is the partner, list order */
    int32_t *trans_entry;
    int32_t *entry_row;       /* per pair entry: its row (the sweep's gather runs over entries) */
    int32_t *trans_lo, *trans_hi; /* n: first and last row naming the particle as partner */
    uint8_t *is_direct;       /* n: whether the sweep finishes the particle as it goes, set by
                               * each sweep for its thread's own rows (sweep.c) */
    /* the sweep's rows of thread t: split[t] to split[t + 1], for split_threads threads (0: even
     * split), moved after each sweep toward equal measured times (sweep.c); the results do not
     * depend on the split */
    int32_t *deferred;        /* n: thread t's deferred particles from split[t] on (sweep.c) */
    int64_t split[DEM_SPLIT_MAX + 1];
    double split_busy[DEM_SPLIT_MAX];
    int split_threads;
    dem_governor gov;         /* how many threads the steps use now (thread_governor.c) */
    int64_t trans_capacity;   /* entries the slot and trans_entry arrays can hold */
    int32_t *cell_of;         /* n */
    int64_t *cell_start;      /* n_cells + 1 */
    int64_t n_cells, cap_cells;
    int32_t *perm;            /* new index -> old index (rebuild scratch) */
    int64_t *cursor;          /* rebuild scratch for counting sorts */
    int64_t cap_cursor;
    int ncell[3];
    double cell_size[3];
    int need_rebuild;
    double r_max;             /* largest radius present */
    int32_t single_material;  /* the material of every particle, or < 0 if they differ (or
                               * there are none); set by the neighbour build */

    uint64_t seed;            /* the caller's run seed, recorded in snapshots */

    /* time */
    int64_t step;
    double time;
    dem_profile profile;
    double rayleigh_cache;    /* < 0: stale */
    int forces_valid;         /* f/t belong to the current state */
};


/* the threads of the next parallel region of a step (<= def.num_threads; thread_governor.c) */
static inline int dem_team(const dem_domain *d) { return d->gov.team; }

/* error reporting: sets the message, returns status */
dem_status dem_fail(dem_domain *d, dem_status s, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
void dem_clear_error(dem_domain *d);
/* A read-back buffer with room for `capacity` items: DEM_OK when capacity >= count, else
 * DEM_ERR_INVALID_ARGUMENT with "<fn>: room for <capacity> <what>, <count> to write" (the error
 * message is the one field of a const domain that a getter writes). */
dem_status dem_check_room(const dem_domain *d, int64_t capacity, int64_t count, const char *what, const char *fn);

/* Internal invariants, checked in builds with -DDEM_CHECKS (the sanitizer build of `make test`);
 * a broken one calls the hook set by dem_set_assert_hook, else prints and aborts. Free of cost
 * otherwise. */
void dem_assert_fail(const char *expr, const char *file, int line);
#ifdef DEM_CHECKS
#define DEM_ASSERT(cond) ((cond) ? (void)0 : dem_assert_fail(#cond, __FILE__, __LINE__))
#else
#define DEM_ASSERT(cond) ((void)0)
#endif

/* materials.c */
const pair_props *dem_pair_props(const dem_domain *d, int a, int b);
void dem_pair_recompute(dem_domain *d, int a, int b);

/* restitution.c: damping factor that delivers restitution e with a force clipped at zero */
double dem_damping_factor_for_restitution(double e);
/* delivered restitution of the continuous clipped model for a damping factor (for tests) */
double dem_restitution_for_damping_factor(double factor);

/* neighbor.c */
extern const double dem_image_sign[27][3]; /* periodic image code -> shift in box lengths */

/* Pair-list entry k of row i as the stress and the contact list read it: n = x_i - x_j (j's
 * periodic image), *dist = |n|; returns the overlap r_i + r_j - |n| (<= 0: not touching). */
static inline double dem_pair_separation(const dem_domain *d, int64_t i, int64_t k, double n[3], double *dist)
{
    const pair_list *pl = &d->pairs_cur;
    const int32_t j = pl->j[k];
    double r2 = 0.0;
    for (int a = 0; a < 3; a++) {
        n[a] = d->x[3 * i + a] - (d->x[3 * j + a] + dem_image_sign[pl->image[k]][a] * (d->def.hi[a] - d->def.lo[a]));
        r2 += n[a] * n[a];
    }
    *dist = sqrt(r2);
    return d->radius[i] + d->radius[j] - *dist;
}
dem_status dem_neighbor_rebuild(dem_domain *d, const unsigned char *remove_mask);
int dem_neighbor_stencil_ok(const dem_domain *d, char *why, size_t why_size);

/* plane_contact.c: plane-wall contacts of particle i added to f/t (*bad: i if an overlap runs
 * away, min), and the messages for a runaway overlap at pair entry k / at particle i. */
void dem_wall_contacts(dem_domain *d, int64_t i, double dt_hist, double *f, double *t, int64_t *bad);
dem_status dem_report_runaway_pair(dem_domain *d, int64_t k);
dem_status dem_report_runaway_wall(dem_domain *d, int64_t i);

/* mesh_contact.c: the mesh contacts of rows [i0, i1) evaluated into their entries (force,
 * torque, springs; *bad: the first particle whose overlap runs away or that too many
 * triangles touch), the law in batches through `scratch`; then, at the particle's finish,
 * their sum added to its f/t. */
struct pair_batch;
void dem_mesh_contacts_rows(dem_domain *d, int64_t i0, int64_t i1, double dt_hist, struct pair_batch *scratch,
                            int64_t *bad);
void dem_mesh_contacts_add(const dem_domain *d, int64_t i, double *f, double *t);
/* a scratch batch per sweep thread where there are mesh walls (0: out of memory) */
int dem_mesh_scratch_reserve(dem_domain *d);
dem_status dem_report_runaway_mesh(dem_domain *d, int64_t i);

/* mesh_bins.c: candidate triangles of every particle (called by the neighbour build) */
dem_status dem_mesh_candidates(dem_domain *d);
/* forget an entry's contact: inactive, no history, no force, point or normal */
void dem_tri_entry_clear(tri_list *tl, int64_t k);
void dem_mesh_free_all(dem_domain *d);

/* materials.c: a material's shear modulus (given, or E / (2 (1 + nu))) */
double dem_material_shear_modulus(const dem_material_def *m);

/* balance.c: the sweep's row split d->split for nth threads (prepared before a sweep, moved
 * toward the measured row times d->split_busy after it) */
void dem_split_prepare(dem_domain *d, int nth);
void dem_split_rebalance(dem_domain *d, int nth);

/* mesh_build.c: welding triangle corners (9 doubles each) into m; finishing a mesh from
 * x_ref/tri (edges, world, normals; 0: out of memory); adding a finished mesh without the
 * overlap check; freeing one */
dem_status dem_mesh_build(dem_domain *d, const double *corner, int64_t n, double tol_user, mesh_wall *m,
                          const char *what);
int dem_mesh_finish(mesh_wall *m);
dem_status dem_mesh_append(dem_domain *d, mesh_wall *m, const char *what, int *out);
void dem_mesh_free(mesh_wall *m);
/* mesh_cut.c: the first of n particles (x, r) that mesh m cuts, or -1 */
int64_t dem_mesh_first_cut(const dem_domain *d, const mesh_wall *m, int64_t n, const double *x, const double *r);

/* particles.c: room for n particles and ids below next_id (0: out of memory) */
int dem_particles_reserve(dem_domain *d, int64_t n, int64_t next_id);

/* mesh_motion.c: servo update from the forces of the step just computed, then the rigid
 * motion of every moving mesh over dt (keeps d->mesh_disp up to date) */
void dem_meshes_update_servos(dem_domain *d);
void dem_meshes_move(dem_domain *d, double dt);
void dem_mesh_update_world(mesh_wall *m);
/* m->disp: its largest vertex displacement from x_build */
void dem_mesh_measure_disp(mesh_wall *m);
/* first of the n particles (x, r) that a mesh cuts (*which_mesh), or -1 */
int64_t dem_meshes_cut_particles(const dem_domain *d, int64_t n, const double *x, const double *r, int *which_mesh);
/* force the particles exert on mesh m during the last step (N) */
void dem_mesh_total_force(const dem_domain *d, int m, double force[3]);
/* wall_mean_force.c: add the force of the step just computed, times dt, to every averaging
 * mesh and plane wall */
void dem_walls_accumulate_mean_force(dem_domain *d, double dt);

/* neighbor.c: frees the build's scratch */
void dem_neighbor_free_scratch(dem_domain *d);

/* step.c */
double dem_rayleigh_time(dem_domain *d);

/* effects.c */
typedef struct dem_effect_contact {
    double n[3];        /* unit normal, from partner towards particle i */
    double overlap;     /* m */
    double distance;    /* m, centre distance (pair) or centre-to-plane distance (wall) */
    double radius_i, radius_j; /* radius_j = 0 for a wall */
    double normal_force;/* N, repulsive elastic + damping part already computed (>= 0) */
    double r_eff;       /* m, R* (the radius for a wall) */
    double wrel[3];     /* rad/s, angular velocity of i minus the partner's */
    double inv_inertia; /* 1/I_i + 1/I_j, 1/(kg m^2) (a wall: 1/I_i); spheres: I = 2/5 m r^2 */
    double tangential_stiffness; /* N/m, the Mindlin k_t = 8 G* sqrt(R* overlap) */
    double vt[3];       /* m/s, tangential velocity of i relative to the partner at the contact */
} dem_effect_contact;
/* The same contacts as arrays, m of them (the batch loop's view; every array m long). No
 * wrel or inv_inertia: an effect that needs them gives no batch kernel. */
typedef struct dem_effect_batch {
    int m;
    const double *n[3], *overlap, *distance, *radius_i, *radius_j, *normal_force, *r_eff, *tangential_stiffness;
} dem_effect_batch;
typedef struct dem_effect_param {
    const char *name, *unit;
    double neutral, min, max;
} dem_effect_param;
typedef struct dem_effect_desc {
    const char *name, *summary;
    int n_params;
    dem_effect_param params[DEM_MAX_EFFECT_PARAMS];
    /* optional: returns the extra normal force (N, positive = repulsive) */
    double (*normal_force)(const dem_effect_contact *c, const double *params);
    /* optional: adds a tangential force on i to force[3] (the partner gets the opposite; its
     * torques follow from the lever arms as the friction's do) */
    void (*tangential_force)(const dem_effect_contact *c, const double *params, double force[3]);
    /* optional: adds a torque on i to torque[3] (the partner gets the opposite) */
    void (*torque)(const dem_effect_contact *c, const double *params, double torque[3]);
    /* optional, for speed, for an effect with a normal_force kernel only: adds that kernel's
     * value for every contact of the batch b to fn_total[q] — bitwise what normal_force gives
     * (the same operations: write the formula once, inline, and call it from both), in a loop
     * the compiler can vectorise. tests/c/test_effects.c compares the two for every effect. */
    void (*normal_force_batch)(const dem_effect_batch *b, const double *params, double *fn_total);
} dem_effect_desc;
const dem_effect_desc *dem_effect_get(int index);
int dem_effect_find(const char *name);

/* small helpers */
void *dem_realloc_array(void *p, size_t count, size_t elem);
/* Row offsets of a list for n rows (n + 1 entries) in *start, grown (by half again) only when
 * *cap is too small, so a build at the same size allocates nothing; 0: out of memory. */
int dem_reserve_rows(int64_t **start, int64_t *cap, int64_t n);
/* Realloc every array to count elements of elem bytes; 0 if any failed (those that
 * succeeded stay valid and grown). */
int dem_realloc_all(void **arrays[], int n_arrays, size_t count, size_t elem);
int dem_is_finite(double x);

#endif
