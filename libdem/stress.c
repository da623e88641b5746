/* Love–Weber average stress in a region: contact part from every contact of every particle
 * whose centre is inside (pairs, plane walls, mesh walls), kinetic part from the velocity
 * fluctuations about the region's mean. Pair contacts act at the point both lever arms
 * share; wall contacts at the wall surface, so that for a bulk at rest filling a container
 * the stress integral equals the boundary tractions' moment exactly. Uses the contact forces of the last step, which
 * belong to the current positions (a step ends with a force evaluation). */
#include "internal.h"
#include <math.h>
#include <string.h>

dem_region dem_default_region(void)
{
    dem_region r;
    memset(&r, 0, sizeof r);
    r.kind = DEM_REGION_BOX;
    r.hi[0] = r.hi[1] = r.hi[2] = 1.0;
    r.axis = 2;
    r.r_outer = 1.0;
    r.h_hi = 1.0;
    r.angle_lo = -DEM_PI;
    r.angle_hi = DEM_PI;
    return r;
}

static int inside(const dem_region *g, const double *x)
{
    if (g->kind == DEM_REGION_BOX) {
        for (int a = 0; a < 3; a++)
            if (x[a] < g->lo[a] || x[a] > g->hi[a]) return 0;
        return 1;
    }
    const int a = g->axis, u = (a + 1) % 3, v = (a + 2) % 3;
    const double h = x[a] - g->centre[a], du = x[u] - g->centre[u], dv = x[v] - g->centre[v];
    if (h < g->h_lo || h > g->h_hi) return 0;
    const double r2 = du * du + dv * dv;
    if (r2 > g->r_outer * g->r_outer) return 0;
    if (g->kind == DEM_REGION_CYLINDER) return 1;
    if (r2 < g->r_inner * g->r_inner) return 0;
    double ang = atan2(dv, du); /* (-pi, pi]: shift into [angle_lo, angle_lo + 2 pi) */
    while (ang < g->angle_lo) ang += 2.0 * DEM_PI;
    while (ang >= g->angle_lo + 2.0 * DEM_PI) ang -= 2.0 * DEM_PI;
    return ang <= g->angle_hi;
}

static dem_status check_region(dem_domain *d, const dem_region *g, double *volume)
{
    const char *fn = "dem_region_stress";
    switch (g->kind) {
    case DEM_REGION_BOX:
        *volume = 1.0;
        for (int a = 0; a < 3; a++) {
            if (!dem_is_finite(g->lo[a]) || !dem_is_finite(g->hi[a]) || !(g->hi[a] > g->lo[a]))
                return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: box needs finite lo < hi on every axis (axis %d)", fn, a);
            *volume *= g->hi[a] - g->lo[a];
        }
        return DEM_OK;
    case DEM_REGION_CYLINDER:
    case DEM_REGION_ANNULAR_SECTOR: {
        if (g->axis < 0 || g->axis > 2) return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: axis must be 0, 1 or 2", fn);
        double vals[] = {g->centre[0], g->centre[1], g->centre[2], g->r_inner, g->r_outer, g->h_lo, g->h_hi, g->angle_lo, g->angle_hi};
        for (size_t k = 0; k < sizeof vals / sizeof vals[0]; k++)
            if (!dem_is_finite(vals[k])) return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: region values must be finite", fn);
        if (!(g->h_hi > g->h_lo)) return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: need h_lo < h_hi", fn);
        double ri = g->kind == DEM_REGION_CYLINDER ? 0.0 : g->r_inner;
        if (!(g->r_outer > ri) || ri < 0.0)
            return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: need 0 <= r_inner < r_outer (got %g, %g)", fn, ri, g->r_outer);
        double span = g->kind == DEM_REGION_CYLINDER ? 2.0 * DEM_PI : g->angle_hi - g->angle_lo;
        if (!(span > 0.0) || span > 2.0 * DEM_PI + 1e-12)
            return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: angle_hi - angle_lo must be in (0, 2 pi], got %g", fn, span);
        *volume = 0.5 * span * (g->r_outer * g->r_outer - ri * ri) * (g->h_hi - g->h_lo);
        return DEM_OK;
    }
    default:
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: unknown region kind %d", fn, (int)g->kind);
    }
}

/* s -= f (x) l */
static void add_contact(double *s, const double *f, const double *l)
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) s[3 * i + j] -= f[i] * l[j];
}

typedef struct contact_stress {
    const dem_region *g;
    double *s;  /* the contact part of the stress (9), volume not yet divided */
    int in_i;   /* whether the visited particle's centre is in the region */
} contact_stress;

/* One contact's share -f (x) l, l from the particle's centre to the contact point: a pair adds
 * to both sides whose particle is in the region, a wall contact to its particle's. */
static void add_visited(const dem_domain *d, const contact_view *c, void *ctx)
{
    const contact_stress *cs = ctx;
    const int64_t i = c->i;
    const double *xi = d->x + 3 * i;
    const int in_i = cs->in_i;
    if (c->kind == DEM_CONTACT_PARTICLE) {
        const int in_j = inside(cs->g, d->x + 3 * (int64_t)c->j);
        const double *f = c->force, *n = c->n, r = c->dist; /* force on i */
        const double ci = d->radius[i] - 0.5 * c->overlap, cj = d->radius[c->j] - 0.5 * c->overlap;
        if (in_i) {
            double l[3] = {-ci * n[0] / r, -ci * n[1] / r, -ci * n[2] / r};
            add_contact(cs->s, f, l);
        }
        if (in_j) {
            double l[3] = {cj * n[0] / r, cj * n[1] / r, cj * n[2] / r}, fj[3] = {-f[0], -f[1], -f[2]};
            add_contact(cs->s, fj, l);
        }
    } else if (in_i && c->kind == DEM_CONTACT_PLANE) {
        double l[3] = {-c->dist * c->n[0], -c->dist * c->n[1], -c->dist * c->n[2]}; /* to the surface */
        add_contact(cs->s, c->force, l);
    } else if (in_i) {
        const double *q = c->point;
        double l[3] = {q[0] - xi[0], q[1] - xi[1], q[2] - xi[2]};
        add_contact(cs->s, c->force, l);
    }
}

dem_status dem_region_stress(dem_domain *d, const dem_region *g, dem_stress *out)
{
    if (!d) return DEM_ERR_NULL;
    if (!g || !out) return dem_fail(d, DEM_ERR_NULL, "dem_region_stress: region and out must not be NULL");
    double volume = 0.0;
    dem_status st = check_region(d, g, &volume);
    if (st != DEM_OK) return st;
    if (d->n > 0 && (d->need_rebuild || !d->forces_valid)) { /* forces must belong to the positions */
        st = dem_domain_step(d, 0);
        if (st < 0) return st;
    }
    memset(out, 0, sizeof *out);
    out->volume = volume;
    double mass = 0.0, mom[3] = {0, 0, 0}, solid = 0.0;
    for (int64_t i = 0; i < d->n; i++) {
        if (!inside(g, d->x + 3 * i)) continue;
        double m = 1.0 / d->inv_mass[i];
        mass += m;
        for (int a = 0; a < 3; a++) mom[a] += m * d->v[3 * i + a];
        solid += 4.0 / 3.0 * DEM_PI * d->radius[i] * d->radius[i] * d->radius[i];
        out->particle_count++;
    }
    if (mass > 0.0)
        for (int a = 0; a < 3; a++) out->mean_velocity[a] = mom[a] / mass;
    out->solid_fraction = solid / volume;

    double *sc = out->contact, *sk = out->kinetic;
    contact_stress cs = {g, sc, 0};
    for (int64_t i = 0; i < d->n; i++) {
        cs.in_i = inside(g, d->x + 3 * i);
        dem_visit_contacts(d, i, VISIT_EVALUATED, add_visited, &cs);
        if (!cs.in_i) continue;
        const double m = 1.0 / d->inv_mass[i];
        double u[3];
        for (int a = 0; a < 3; a++) u[a] = d->v[3 * i + a] - out->mean_velocity[a];
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) sk[3 * a + b] += m * u[a] * u[b];
    }
    for (int k = 0; k < 9; k++) {
        sc[k] /= volume;
        sk[k] /= volume;
        out->total[k] = sc[k] + sk[k];
    }
    dem_clear_error(d);
    return DEM_OK;
}
