/* The thread governor (thread_governor.c): how many of the domain's num_threads threads the
 * next steps use, chosen by measuring. Results do not depend on it (they do not depend on the
 * thread count at all: tests/c/test_determinism.c), only the wall time does. */
#ifndef DEM_THREAD_GOVERNOR_H
#define DEM_THREAD_GOVERNOR_H

typedef struct dem_governor {
    int adaptive;       /* 0: always num_threads */
    int team;           /* threads the next sweep uses, 1 ... num_threads */
    int settled;        /* the team chosen by the last probe (team differs from it during a probe) */
    int probing;        /* the current window measures a probed team */
    int skip;           /* sweeps left out of the window after a team change (wake-up, row split) */
    int steps;          /* the current window: sweeps and their seconds */
    double elapsed;
    double per_step;    /* the settled team's seconds per sweep, its last window */
    double since_probe; /* sweep seconds since the last probe ended */
    double interval;    /* sweep seconds between probes: doubled by each probe that loses */
    int probe_fewer;    /* which neighbour of the settled team the next probe tries */
} dem_governor;

/* Start over with num_threads threads (creation, dem_domain_set_num_threads, adaptation on/off). */
void dem_governor_reset(dem_governor *g, int num_threads, int adaptive);
/* One measured sweep of one step took `seconds` with g->team threads; may change g->team. */
void dem_governor_record(dem_governor *g, int num_threads, double seconds);

#endif
