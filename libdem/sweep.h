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

sweep_result dem_sweep(dem_domain *d, double dt_hist, sweep_mode mode);
void dem_sweep_result_init(sweep_result *r);
void dem_sweep_bounds(const dem_domain *d, double *lo, double *hi);
/* Opening half kick and drift of particle p; vl/wl hold its velocities and are updated. */
void dem_open_step(dem_domain *d, int64_t p, const double *f, const double *t, double *vl, double *wl,
                   const double *lo, const double *hi, sweep_result *res);

#endif
