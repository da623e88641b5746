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

/* One overlapping contact: counted, its Hertz energy and overlap ratio. */
static void add_contact(const dem_domain *d, const contact_view *c, void *ctx)
{
    dem_diagnostics *out = ctx;
    const int64_t i = c->i;
    const double e_star = dem_pair_props(d, d->mat[i], c->partner_material)->e_star;
    out->contact_count++;
    if (c->kind == DEM_CONTACT_PARTICLE) {
        const double ri = d->radius[i], rj = d->radius[c->j];
        out->elastic_energy += hertz_energy(e_star, ri * rj / (ri + rj), c->overlap);
        const double ratio = c->overlap / fmin(ri, rj);
        if (ratio > out->max_overlap_ratio) out->max_overlap_ratio = ratio;
        return;
    }
    out->wall_contact_count++;
    out->elastic_energy += hertz_energy(e_star, d->radius[i], c->overlap);
    const double ratio = c->overlap / d->radius[i];
    if (ratio > out->max_overlap_ratio) out->max_overlap_ratio = ratio;
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
    for (int64_t i = 0; i < d->n; i++) dem_visit_contacts(d, i, VISIT_GEOMETRIC, add_contact, out);
    return DEM_OK;
}
