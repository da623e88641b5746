/* Thread balance of the force sweep (sweep.c): the split of the particle rows among the
 * threads, moved after each sweep toward equal measured row times. Results do not depend on
 * the split (sweep.c says why), only the wall time does. */
#include "internal.h"

/* Make d->split fit n rows and nth threads: kept (rescaled if n changed) when it was made for
 * nth threads, else even; split_threads = 0 where nth is beyond DEM_SPLIT_MAX. One thread has
 * nothing to split: the split of a larger team is left as it is for the team's return (the
 * thread governor's probes of one thread; thread_governor.c). */
void dem_split_prepare(dem_domain *d, int nth)
{
    const int64_t n = d->n;
    if (nth == 1) return;
    if (nth < 1 || nth > DEM_SPLIT_MAX) {
        d->split_threads = 0;
        return;
    }
    if (d->split_threads != nth) {
        for (int t = 0; t <= nth; t++) d->split[t] = n * t / nth;
        d->split_threads = nth;
    } else if (d->split[nth] != n) { /* particles were added or removed: same fractions */
        const int64_t old = d->split[nth] > 0 ? d->split[nth] : 1;
        for (int t = 1; t < nth; t++) d->split[t] = d->split[t] * n / old;
        d->split[nth] = n;
    }
}

/* Move the split points halfway toward where the measured row times say each thread would
 * get an equal share (the time per row taken as even within each thread's rows). */
void dem_split_rebalance(dem_domain *d, int nth)
{
    double cum[DEM_SPLIT_MAX + 1];
    cum[0] = 0.0;
    for (int t = 0; t < nth; t++) cum[t + 1] = cum[t] + (d->split_busy[t] > 1e-9 ? d->split_busy[t] : 1e-9);
    int64_t next[DEM_SPLIT_MAX + 1];
    next[0] = 0;
    next[nth] = d->split[nth];
    int j = 0;
    for (int t = 1; t < nth; t++) {
        const double target = cum[nth] * t / nth;
        while (j < nth - 1 && cum[j + 1] <= target) j++;
        const double at = (double)d->split[j] + (target - cum[j]) / (cum[j + 1] - cum[j]) * (double)(d->split[j + 1] - d->split[j]);
        int64_t p = (int64_t)(0.5 * ((double)d->split[t] + at) + 0.5);
        if (p < next[t - 1]) p = next[t - 1];
        if (p > next[nth]) p = next[nth];
        next[t] = p;
    }
    for (int t = 1; t < nth; t++) d->split[t] = next[t];
}
