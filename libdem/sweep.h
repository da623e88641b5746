/* The fused force + integration sweep (sweep.c). */
#ifndef DEM_SWEEP_H
#define DEM_SWEEP_H

#include "internal.h"

typedef enum sweep_mode {
    SWEEP_FORCES = 0,     /* forces of the current state only (refresh) */
    SWEEP_CLOSE = 1,      /* forces, then the closing half kick (last step of a call) */
    SWEEP_CLOSE_OPEN = 2  /* forces, closing half kick, next step's half kick and drift */
} sweep_mode;

/* Outcome: largest squared displacement since the list build, and the first problems
 * (INT64_MAX when none): particle with a non-finite state, particle outside a closed axis,
 * particle with a runaway wall overlap, pair entry with a runaway overlap. */
typedef struct sweep_result {
    double maxdisp2;
    int64_t bad_nan, bad_out, bad_wall, bad_pair;
} sweep_result;

/* The particle arrays and step constants the sweep's inner code uses, copied into a local
 * variable of each thread. Why: the activity flags are stored through uint8_t pointers, which
 * may alias any memory the compiler cannot prove private, so read from the domain (reachable
 * by every thread) each array pointer and constant was loaded again after every such store;
 * a local whose address does not escape stays in registers. */
typedef struct sweep_view {
    double *x, *v, *w, *f, *t, *slot;
    const double *x_build, *inv_mass, *inv_inertia;
    double dt, half, gravity[3], max_overlap_ratio;
    double lo[3], hi[3]; /* closed-axis bounds (+-DBL_MAX on periodic axes) */
} sweep_view;

sweep_result dem_sweep(dem_domain *d, double dt_hist, sweep_mode mode);
void dem_sweep_result_init(sweep_result *r);
void dem_sweep_view(dem_domain *d, sweep_view *s);
/* Opening half kick and drift of particle p; vl/wl hold its velocities and are updated. */
void dem_open_step(const sweep_view *s, int64_t p, const double *f, const double *t, double *vl, double *wl,
                   sweep_result *res);

#endif
