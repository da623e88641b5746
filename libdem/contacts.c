/* The contact list of the current state for users (force chains, per-contact analysis, output):
 * the same entries and forces the force sweep used and the Love-Weber stress reads, in the
 * particles' memory order. */
#include <math.h>

#include "internal.h"

/* friction: the pair's mu_s; a contact slides when its tangential force is at mu_s times the
 * normal force (to round-off); with cohesion the law caps at mu_s times the repulsive part, which
 * this normal force (repulsion less cohesion) understates: such contacts may read as sliding. */
static void put(dem_contact *c, dem_particle_id i, dem_particle_id j, int kind, int wall, int64_t tri, const double *point,
                const double *normal, const double *force, double overlap, double friction)
{
    const double fn = force[0] * normal[0] + force[1] * normal[1] + force[2] * normal[2];
    const double t[3] = {force[0] - fn * normal[0], force[1] - fn * normal[1], force[2] - fn * normal[2]};
    const double ft = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    c->normal_force = fn;
    c->tangential_force = ft;
    c->sliding = ft > 0.0 && ft >= friction * fn * (1.0 - 1e-9);
    c->reserved = 0;
    c->i = i;
    c->j = j;
    c->kind = kind;
    c->wall = wall;
    c->triangle = tri;
    for (int a = 0; a < 3; a++) {
        c->point[a] = point[a];
        c->normal[a] = normal[a];
        c->force[a] = force[a];
    }
    c->overlap = overlap;
}

typedef struct contact_sink {
    dem_contact *out;
    int64_t capacity, m;
} contact_sink;

/* One visited contact into the user's array (counted even when the array is full). */
static void put_contact(const dem_domain *d, const contact_view *c, void *ctx)
{
    contact_sink *s = ctx;
    if (s->m < s->capacity) {
        const int64_t i = c->i, k = c->k;
        const double *xi = d->x + 3 * i;
        const double friction = dem_pair_props(d, d->mat[i], c->partner_material)->def.friction;
        double q[3];
        if (c->kind == DEM_CONTACT_PARTICLE) {
            const double u[3] = {c->n[0] / c->dist, c->n[1] / c->dist, c->n[2] / c->dist};
            for (int a = 0; a < 3; a++) q[a] = xi[a] - (d->radius[i] - 0.5 * c->overlap) * u[a];
            put(s->out + s->m, d->id[i], d->id[c->j], DEM_CONTACT_PARTICLE, -1, -1, q, u, c->force, c->overlap, friction);
        } else if (c->kind == DEM_CONTACT_PLANE) {
            for (int a = 0; a < 3; a++) q[a] = xi[a] - c->dist * c->n[a];
            put(s->out + s->m, d->id[i], -1, DEM_CONTACT_PLANE, d->walls_cur.wall[k], -1, q, c->n, c->force, c->overlap,
                friction);
        } else {
            put(s->out + s->m, d->id[i], -1, DEM_CONTACT_MESH, d->tris_cur.mesh[k], d->tris_cur.tri[k], c->point, c->n,
                c->force, c->overlap, friction);
        }
    }
    s->m++;
}

dem_status dem_contacts_get(dem_domain *d, dem_contact *out, int64_t capacity, int64_t *count)
{
    if (!d) return DEM_ERR_NULL;
    if (!count) return dem_fail(d, DEM_ERR_NULL, "dem_contacts_get: count must not be NULL");
    if (capacity < 0 || (capacity > 0 && !out))
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_contacts_get: capacity %lld without an output array",
                        (long long)capacity);
    if (d->n > 0 && (d->need_rebuild || !d->forces_valid)) {
        dem_status s = dem_domain_step(d, 0);
        if (s < 0) return s;
    }
    contact_sink sink = {out, capacity, 0};
    for (int64_t i = 0; i < d->n; i++) dem_visit_contacts(d, i, VISIT_EVALUATED, put_contact, &sink);
    const int64_t m = sink.m;
    *count = m;
    if (capacity > 0 && capacity < m)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_contacts_get: %lld contacts, room for %lld (the first written)",
                        (long long)m, (long long)capacity);
    dem_clear_error(d);
    return DEM_OK;
}
