/* Diagnostics of the current state: energies, momentum, contacts, overlap. Serial sums in
 * index order, so they are as deterministic as the state itself. */
#include "internal.h"
#include <math.h>
#include <string.h>

/* Hertz elastic energy stored at overlap delta: integral of (4/3) E* sqrt(R*) d^(3/2). */
static double hertz_energy(double e_star, double r_eff, double delta)
{
    return 8.0 / 15.0 * e_star * sqrt(r_eff) * pow(delta, 2.5);
}

dem_status dem_domain_diagnostics(dem_domain *d, dem_diagnostics *out)
{
    if (!d) return DEM_ERR_NULL;
    if (!out) return dem_fail(d, DEM_ERR_NULL, "dem_domain_diagnostics: out must not be NULL");
    memset(out, 0, sizeof *out);
    out->step = d->step;
    out->time = d->time;
    out->particle_count = d->n;
    if (d->n == 0) return DEM_OK;
    if (d->need_rebuild) {
        dem_status s = dem_neighbor_rebuild(d, NULL);
        if (s != DEM_OK) return s;
    }
    for (int64_t i = 0; i < d->n; i++) {
        double m = 1.0 / d->inv_mass[i], I = 1.0 / d->inv_inertia[i];
        const double *v = d->v + 3 * i, *w = d->w + 3 * i;
        out->kinetic_energy += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) +
                               0.5 * I * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        for (int a = 0; a < 3; a++) out->momentum[a] += m * v[a];
    }
    const pair_list *pl = &d->pairs_cur;
    for (int64_t i = 0; i < d->n; i++) {
        for (int64_t k = pl->start[i]; k < pl->start[i + 1]; k++) {
            int32_t j = pl->j[k];
            double r2 = 0.0;
            for (int a = 0; a < 3; a++) {
                double u = d->x[3 * i + a] - d->x[3 * j + a] -
                           dem_image_sign[pl->image[k]][a] * (d->def.hi[a] - d->def.lo[a]);
                r2 += u * u;
            }
            double delta = d->radius[i] + d->radius[j] - sqrt(r2);
            if (delta <= 0.0) continue;
            out->contact_count++;
            const pair_props *pp = dem_pair_props(d, d->mat[i], d->mat[j]);
            out->elastic_energy += hertz_energy(pp->e_star, d->radius[i] * d->radius[j] / (d->radius[i] + d->radius[j]), delta);
            double ratio = delta / fmin(d->radius[i], d->radius[j]);
            if (ratio > out->max_overlap_ratio) out->max_overlap_ratio = ratio;
        }
        const wall_list *wl = &d->walls_cur;
        for (int64_t k = wl->start[i]; k < wl->start[i + 1]; k++) {
            const plane_wall *pw = &d->walls[wl->wall[k]];
            double delta = d->radius[i] - (d->x[3 * i + pw->def.axis] - pw->def.position) * pw->def.side;
            if (delta <= 0.0) continue;
            out->contact_count++;
            out->wall_contact_count++;
            out->elastic_energy += hertz_energy(dem_pair_props(d, d->mat[i], pw->def.material.index)->e_star, d->radius[i], delta);
            double ratio = delta / d->radius[i];
            if (ratio > out->max_overlap_ratio) out->max_overlap_ratio = ratio;
        }
        const tri_list *tl = &d->tris_cur;
        for (int64_t k = tl->start[i]; k < tl->start[i + 1]; k++) { /* accepted mesh contacts */
            if (!tl->active[k]) continue;
            const double *q = tl->point + 3 * k, *p = d->x + 3 * i;
            double u2 = 0.0;
            for (int a = 0; a < 3; a++) u2 += (p[a] - q[a]) * (p[a] - q[a]);
            double delta = d->radius[i] - sqrt(u2);
            if (delta <= 0.0) continue;
            out->contact_count++;
            out->wall_contact_count++;
            int wm = d->meshes[tl->mesh[k]].material;
            out->elastic_energy += hertz_energy(dem_pair_props(d, d->mat[i], wm)->e_star, d->radius[i], delta);
            double ratio = delta / d->radius[i];
            if (ratio > out->max_overlap_ratio) out->max_overlap_ratio = ratio;
        }
    }
    return DEM_OK;
}
