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
    const pair_list *pl = &d->pairs_cur;
    const wall_list *wl = &d->walls_cur;
    const tri_list *tl = &d->tris_cur;
    int64_t m = 0;
    for (int64_t i = 0; i < d->n; i++) {
        const double *xi = d->x + 3 * i;
        for (int64_t k = pl->start ? pl->start[i] : 0; pl->start && k < pl->start[i + 1]; k++) {
            if (!pl->active[k]) continue;
            const int32_t j = pl->j[k];
            double n[3], r;
            const double delta = dem_pair_separation(d, i, k, n, &r);
            if (delta <= 0.0) continue;
            if (m < capacity) {
                double u[3] = {n[0] / r, n[1] / r, n[2] / r}, q[3];
                for (int a = 0; a < 3; a++) q[a] = xi[a] - (d->radius[i] - 0.5 * delta) * u[a];
                put(out + m, d->id[i], d->id[j], DEM_CONTACT_PARTICLE, -1, -1, q, u, d->slot + 6 * k, delta,
                    dem_pair_props(d, d->mat[i], d->mat[j])->def.friction);
            }
            m++;
        }
        for (int64_t k = wl->start ? wl->start[i] : 0; wl->start && k < wl->start[i + 1]; k++) {
            const plane_wall *pw = &d->walls[wl->wall[k]];
            const double dist = (xi[pw->def.axis] - pw->def.position) * pw->def.side;
            if (dist >= d->radius[i]) continue;
            if (m < capacity) {
                double q[3];
                for (int a = 0; a < 3; a++) q[a] = xi[a] - dist * pw->normal[a];
                put(out + m, d->id[i], -1, DEM_CONTACT_PLANE, wl->wall[k], -1, q, pw->normal, wl->force + 3 * k,
                    d->radius[i] - dist, dem_pair_props(d, d->mat[i], pw->def.material.index)->def.friction);
            }
            m++;
        }
        for (int64_t k = tl->start ? tl->start[i] : 0; tl->start && k < tl->start[i + 1]; k++) {
            if (!tl->active[k]) continue;
            const double *q = tl->point + 3 * k;
            const double dist = sqrt((xi[0] - q[0]) * (xi[0] - q[0]) + (xi[1] - q[1]) * (xi[1] - q[1]) +
                                     (xi[2] - q[2]) * (xi[2] - q[2]));
            if (m < capacity)
                put(out + m, d->id[i], -1, DEM_CONTACT_MESH, tl->mesh[k], tl->tri[k], q, tl->normal + 3 * k,
                    tl->force + 3 * k, d->radius[i] - dist,
                    dem_pair_props(d, d->mat[i], d->meshes[tl->mesh[k]].material)->def.friction);
            m++;
        }
    }
    *count = m;
    if (capacity > 0 && capacity < m)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_contacts_get: %lld contacts, room for %lld (the first written)",
                        (long long)m, (long long)capacity);
    dem_clear_error(d);
    return DEM_OK;
}
