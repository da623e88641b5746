/* The thread governor: on a shared machine a thread of the team can be descheduled, and every
 * step's barriers then wait for it — a 2-thread run beside one busy process ran 3-9x slower than
 * on 1 thread (studies/JOURNAL.md, "A busy machine"); and a small system (a few thousand spheres)
 * can run slower on more threads when the barriers sleep. So the step loop measures its sweeps
 * and now and then tries a neighbouring team size (half or double the current one, within 1 ...
 * num_threads) for one short window, keeping it when it is clearly faster. A probe that loses
 * doubles the time to the next one (0.25 s of sweeps, up to 8 s; the first probe follows the
 * first window), so a stable choice costs little: a losing probe runs one window (>= 20 ms) on
 * the slower team. */
#include "thread_governor.h"

enum { WINDOW_STEPS = 4, SKIP_STEPS = 1 };
static const double WINDOW_S = 0.02;     /* a window: at least this many sweep seconds ... */
static const double FIRST_INTERVAL = 0.25, LAST_INTERVAL = 8.0;
static const double GAIN = 0.9;          /* a probed team is kept when 10 % faster per sweep */

void dem_governor_reset(dem_governor *g, int num_threads, int adaptive)
{
    *g = (dem_governor){0};
    g->adaptive = adaptive;
    g->team = g->settled = num_threads;
    g->interval = FIRST_INTERVAL;
    g->since_probe = FIRST_INTERVAL; /* the first window is followed by a probe: a short run on a
                                      * busy machine must not wait 0.25 s for its first choice */
    g->probe_fewer = 1;
}

/* The team a probe tries next: alternately half and double the settled one, where they exist. */
static int probe_team(dem_governor *g, int num_threads)
{
    const int fewer = g->settled > 1 ? g->settled / 2 : 0;
    const int more = g->settled < num_threads ? (2 * g->settled < num_threads ? 2 * g->settled : num_threads) : 0;
    const int pick = (g->probe_fewer && fewer) || !more ? fewer : more;
    g->probe_fewer = !g->probe_fewer;
    return pick;
}

void dem_governor_record(dem_governor *g, int num_threads, double seconds)
{
    if (!g->adaptive || num_threads <= 1) {
        g->team = g->settled = num_threads;
        return;
    }
    if (g->settled > num_threads || g->team > num_threads) dem_governor_reset(g, num_threads, g->adaptive);
    if (g->skip > 0) {
        g->skip--;
        return;
    }
    g->steps++;
    g->elapsed += seconds;
    if (g->steps < WINDOW_STEPS || g->elapsed < WINDOW_S) return;
    const double per = g->elapsed / g->steps, window = g->elapsed;
    g->steps = 0;
    g->elapsed = 0.0;
    if (g->probing) {
        g->probing = 0;
        if (per < GAIN * g->per_step) { /* the probed team wins: settle on it, probe again soon */
            g->settled = g->team;
            g->per_step = per;
            g->interval = FIRST_INTERVAL;
        } else {
            g->team = g->settled;
            g->skip = SKIP_STEPS;
            g->interval = 2.0 * g->interval < LAST_INTERVAL ? 2.0 * g->interval : LAST_INTERVAL;
        }
        return;
    }
    g->per_step = per;
    g->since_probe += window;
    if (g->since_probe < g->interval) return;
    g->since_probe = 0.0;
    const int t = probe_team(g, num_threads);
    if (t > 0) {
        g->probing = 1;
        g->team = t;
        g->skip = SKIP_STEPS;
    }
}
