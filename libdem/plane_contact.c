/* Plane-wall contacts (the contact law of contact_law.h against an analytic plane) and the
 * runaway-overlap reports of every contact kind. (Pair contacts: the force sweep, sweep.c.) */
#include "contact_law.h"
#include <math.h>

static const char *runaway_why =
    "(time step too large for the stiffness and speeds, or particles inserted into each other)";

/* Cold path: pair entry k overlapped beyond the limit during this step. */
dem_status dem_report_runaway_pair(dem_domain *d, int64_t k)
{
    const pair_list *pl = &d->pairs_cur;
    int64_t lo = 0, hi = pl->n_rows; /* row of entry k: start[lo] <= k < start[lo + 1] */
    while (hi - lo > 1) {
        int64_t mid = (lo + hi) / 2;
        if (pl->start[mid] <= k) lo = mid;
        else hi = mid;
    }
    return dem_fail(d, DEM_ERR_RUNAWAY_OVERLAP,
                    "runaway overlap during step %lld: particles id %lld and id %lld overlap by more than %g of the "
                    "smaller radius %s",
                    (long long)d->step + 1, (long long)d->id[lo], (long long)d->id[pl->j[k]],
                    d->def.max_overlap_ratio, runaway_why);
}

/* Cold path: particle i overlapped a plane wall beyond the limit during this step. */
dem_status dem_report_runaway_wall(dem_domain *d, int64_t i)
{
    int plane = 0;
    for (int64_t k = d->walls_cur.start[i]; k < d->walls_cur.start[i + 1]; k++) {
        const plane_wall *pw = &d->walls[d->walls_cur.wall[k]];
        double dist = (d->x[3 * i + pw->def.axis] - pw->def.position) * pw->def.side;
        plane |= d->radius[i] - dist > d->def.max_overlap_ratio * d->radius[i];
    }
    if (!plane) return dem_report_runaway_mesh(d, i);
    return dem_fail(d, DEM_ERR_RUNAWAY_OVERLAP,
                    "runaway overlap during step %lld: particle id %lld overlaps a plane wall by more than %g of its "
                    "radius %s",
                    (long long)d->step + 1, (long long)d->id[i], d->def.max_overlap_ratio, runaway_why);
}

/* Plane-wall contacts of particle i, added to f/t (after its pair slots). */
void dem_wall_contacts(dem_domain *d, int64_t i, double dt_hist, double *f, double *t, int64_t *bad)
{
    const wall_list *wl = &d->walls_cur;
    const double *xi_ = d->x + 3 * i, *vi = d->v + 3 * i, *wi = d->w + 3 * i;
    const double ri = d->radius[i];
    const pair_props *row_pairs = d->pairs + (size_t)d->mat[i] * d->n_materials;
    for (int64_t k = wl->start[i]; k < wl->start[i + 1]; k++) {
        const plane_wall *pw = &d->walls[wl->wall[k]];
        const double dist = (xi_[pw->def.axis] - pw->def.position) * pw->def.side;
        double *h = wl->hist + 6 * k, *wf = wl->force + 3 * k;
        if (dist >= ri) {
            for (int a = 0; a < 6; a++) h[a] = 0.0;
            wf[0] = wf[1] = wf[2] = 0.0;
            continue;
        }
        static const double no_spin[3] = {0.0, 0.0, 0.0};
        contact_in c;
        const double ci = wall_contact_in(&c, pw->normal, dist, ri, d->inv_mass[i], vi, wi, pw->def.velocity, no_spin);
        if (c.overlap > d->def.max_overlap_ratio * ri && i < *bad) *bad = i;
        contact_out o;
        contact_law(&row_pairs[pw->def.material.index], &c, dt_hist, h, h + 3, &o);
        for (int a = 0; a < 3; a++) {
            f[a] += o.force[a];
            t[a] += -ci * o.cross[a] + o.mr[a];
            wf[a] = o.force[a];
        }
    }
}
