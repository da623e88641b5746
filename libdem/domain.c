/* Domain life cycle, settings, profile, state hash and memory accounting. */
#include "pair_batch.h"
#include "alloc.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

dem_domain_def dem_default_domain_def(void)
{
    dem_domain_def d;
    memset(&d, 0, sizeof d);
    for (int a = 0; a < 3; a++) {
        d.lo[a] = 0.0;
        d.hi[a] = 0.1;
        d.periodic[a] = 0;
        d.gravity[a] = 0.0;
    }
    d.gravity[2] = -9.81;
    d.dt = 1e-5;
    d.skin = 2e-4;
    d.num_threads = 1;
    d.max_overlap_ratio = 0.3;
    d.insert_overlap_ratio = 1e-3;
    d.reference_velocity = 1.0;
    return d;
}

static int def_error(const dem_domain_def *def, char *why, size_t n)
{
    for (int a = 0; a < 3; a++) {
        if (!dem_is_finite(def->lo[a]) || !dem_is_finite(def->hi[a]) || !(def->hi[a] > def->lo[a])) {
            snprintf(why, n, "domain bounds on axis %d must be finite with hi > lo, got [%g, %g]", a, def->lo[a],
                     def->hi[a]);
            return 1;
        }
        if (!dem_is_finite(def->gravity[a])) {
            snprintf(why, n, "gravity component %d is not finite", a);
            return 1;
        }
    }
    if (!dem_is_finite(def->dt) || def->dt <= 0) {
        snprintf(why, n, "time step dt must be finite and > 0 s, got %g", def->dt);
        return 1;
    }
    if (!dem_is_finite(def->skin) || def->skin <= 0) {
        snprintf(why, n, "neighbour skin must be finite and > 0 m, got %g", def->skin);
        return 1;
    }
    if (def->num_threads < 1 || def->num_threads > 1024) {
        snprintf(why, n, "num_threads must be in [1, 1024], got %d", def->num_threads);
        return 1;
    }
    if (!dem_is_finite(def->max_overlap_ratio) || def->max_overlap_ratio <= 0 || def->max_overlap_ratio > 1) {
        snprintf(why, n, "max_overlap_ratio must be in (0, 1], got %g", def->max_overlap_ratio);
        return 1;
    }
    if (!dem_is_finite(def->insert_overlap_ratio) || def->insert_overlap_ratio < 0 || def->insert_overlap_ratio > 1) {
        snprintf(why, n, "insert_overlap_ratio must be in [0, 1], got %g", def->insert_overlap_ratio);
        return 1;
    }
    if (!dem_is_finite(def->reference_velocity) || def->reference_velocity <= 0) {
        snprintf(why, n, "reference_velocity must be finite and > 0 m/s, got %g", def->reference_velocity);
        return 1;
    }
    return 0;
}

dem_status dem_domain_create(const dem_domain_def *def, dem_domain **out, char *msg, size_t msg_size)
{
    char why[DEM_ERRMSG_SIZE];
    if (msg && msg_size) msg[0] = '\0';
    if (!out) return DEM_ERR_NULL;
    *out = NULL;
    if (!def) {
        if (msg && msg_size) snprintf(msg, msg_size, "dem_domain_create: def must not be NULL");
        return DEM_ERR_NULL;
    }
    if (def_error(def, why, sizeof why)) {
        if (msg && msg_size) snprintf(msg, msg_size, "dem_domain_create: %s", why);
        return DEM_ERR_INVALID_ARGUMENT;
    }
    dem_domain *d = dem_calloc(1, sizeof *d);
    if (!d) {
        if (msg && msg_size) snprintf(msg, msg_size, "dem_domain_create: out of memory");
        return DEM_ERR_NO_MEMORY;
    }
    dem_live_objects(+1);
    d->def = *def;
    d->rayleigh_cache = -1.0;
    d->need_rebuild = 1;
    d->single_material = -1;
    dem_governor_reset(&d->gov, d->def.num_threads, 1);
    *out = d;
    return DEM_OK;
}

static void free_pair_list(pair_list *p)
{
    dem_free(p->start);
    dem_free(p->active);
    dem_free(p->j);
    dem_free(p->image);
    dem_free(p->hist);
}

static void free_wall_list(wall_list *w)
{
    dem_free(w->start);
    dem_free(w->wall);
    dem_free(w->hist);
    dem_free(w->force);
}

void dem_domain_destroy(dem_domain *d)
{
    if (!d) return;
    dem_free(d->materials);
    dem_free(d->pairs);
    double *dbl[] = {d->x, d->v, d->w, d->f, d->t, d->x_build, d->radius, d->inv_mass, d->inv_inertia};
    for (size_t k = 0; k < sizeof dbl / sizeof dbl[0]; k++) dem_free(dbl[k]);
    dem_free(d->mat);
    dem_free(d->id);
    dem_free(d->index_of_id);
    dem_free(d->walls);
    dem_mesh_free_all(d);
    dem_neighbor_free_scratch(d);
    free_pair_list(&d->pairs_cur);
    free_pair_list(&d->pairs_old);
    free_wall_list(&d->walls_cur);
    free_wall_list(&d->walls_old);
    dem_free(d->slot);
    dem_free(d->trans_start);
    dem_free(d->trans_entry);
    dem_free(d->entry_row);
    dem_free(d->cell_of);
    dem_free(d->trans_lo);
    dem_free(d->deferred);
    dem_free(d->trans_hi);
    dem_free(d->is_direct);
    dem_free(d->cell_start);
    dem_free(d->perm);
    dem_free(d->cursor);
    dem_free(d);
    dem_live_objects(-1);
}

dem_status dem_domain_get_def(const dem_domain *d, dem_domain_def *def)
{
    if (!d || !def) return DEM_ERR_NULL;
    *def = d->def;
    return DEM_OK;
}

dem_status dem_domain_set_dt(dem_domain *d, double dt)
{
    if (!d) return DEM_ERR_NULL;
    if (!dem_is_finite(dt) || dt <= 0)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_domain_set_dt: dt must be finite and > 0 s, got %g", dt);
    d->def.dt = dt;
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_domain_set_gravity(dem_domain *d, const double g[3])
{
    if (!d) return DEM_ERR_NULL;
    if (!g) return dem_fail(d, DEM_ERR_NULL, "dem_domain_set_gravity: gravity must not be NULL");
    for (int a = 0; a < 3; a++)
        if (!dem_is_finite(g[a]))
            return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_domain_set_gravity: component %d is not finite", a);
    for (int a = 0; a < 3; a++) d->def.gravity[a] = g[a];
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_domain_set_num_threads(dem_domain *d, int num_threads)
{
    if (!d) return DEM_ERR_NULL;
    if (num_threads < 1 || num_threads > 1024)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_domain_set_num_threads: must be in [1, 1024], got %d",
                        num_threads);
    d->def.num_threads = num_threads;
    dem_governor_reset(&d->gov, num_threads, d->gov.adaptive);
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_domain_set_adaptive_threads(dem_domain *d, int adaptive)
{
    if (!d) return DEM_ERR_NULL;
    if (adaptive != 0 && adaptive != 1)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_domain_set_adaptive_threads: must be 0 or 1, got %d", adaptive);
    dem_governor_reset(&d->gov, d->def.num_threads, adaptive);
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_domain_profile(const dem_domain *d, dem_profile *p)
{
    if (!d || !p) return DEM_ERR_NULL;
    *p = d->profile;
    p->neighbor_pairs = d->pairs_cur.count;
    return DEM_OK;
}

dem_status dem_domain_profile_reset(dem_domain *d)
{
    if (!d) return DEM_ERR_NULL;
    memset(&d->profile, 0, sizeof d->profile);
    return DEM_OK;
}

static uint64_t fnv1a(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = data;
    for (size_t k = 0; k < n; k++) {
        h ^= p[k];
        h *= 1099511628211ULL;
    }
    return h;
}

dem_status dem_domain_state_hash(const dem_domain *d, uint64_t *hash)
{
    if (!d || !hash) return DEM_ERR_NULL;
    uint64_t h = 1469598103934665603ULL;
    for (dem_particle_id id = 0; id < d->next_id; id++) {
        int32_t i = d->index_of_id[id];
        if (i < 0) continue;
        h = fnv1a(h, &id, sizeof id);
        h = fnv1a(h, d->x + 3 * i, 3 * sizeof(double));
        h = fnv1a(h, d->v + 3 * i, 3 * sizeof(double));
        h = fnv1a(h, d->w + 3 * i, 3 * sizeof(double));
    }
    *hash = h;
    return DEM_OK;
}

size_t dem_domain_memory_bytes(const dem_domain *d)
{
    if (!d) return 0;
    size_t b = sizeof *d;
    size_t cap = (size_t)d->cap;
    b += cap * (6 * 3 + 3) * sizeof(double); /* x v w f t x_build; radius inv_mass inv_inertia */
    b += cap * (sizeof(int32_t) * 6 + sizeof(dem_particle_id) + sizeof(int64_t) + 1); /* mat cell_of perm trans_lo/hi deferred id trans_start is_direct */
    b += (size_t)(d->walls_cur.start ? 2 * (cap + 1) * sizeof(int64_t) : 0);     /* wall list offsets */
    b += (size_t)d->cap_ids * sizeof(int32_t);
    b += (size_t)d->cap_cells * sizeof(int64_t) + (size_t)d->cap_cursor * sizeof(int64_t);
    const pair_list *pls[2] = {&d->pairs_cur, &d->pairs_old};
    for (int k = 0; k < 2; k++)
        b += (size_t)pls[k]->capacity * (sizeof(int32_t) + 2 + 6 * sizeof(double)) +
             (size_t)(pls[k]->n_rows + 1) * sizeof(int64_t);
    b += (size_t)d->trans_capacity * (6 * sizeof(double) + 2 * sizeof(int32_t)); /* slot trans_entry entry_row */
    const wall_list *wls[2] = {&d->walls_cur, &d->walls_old};
    for (int k = 0; k < 2; k++) b += (size_t)wls[k]->capacity * (sizeof(int32_t) + 9 * sizeof(double));
    b += (size_t)d->n_materials * d->n_materials * (sizeof(pair_props) + 1);
    b += (size_t)d->cap_walls * sizeof(plane_wall);
    const tri_list *tls[2] = {&d->tris_cur, &d->tris_old}; /* mesh walls and their candidates */
    for (int k = 0; k < 2; k++)
        b += (size_t)tls[k]->capacity * (2 * sizeof(int32_t) + 1 + 18 * sizeof(double)) +
             (size_t)(tls[k]->start ? tls[k]->n_rows + 1 : 0) * sizeof(int64_t);
    b += (size_t)d->cap_meshes * sizeof(mesh_wall) + (size_t)d->mesh_scratch_threads * sizeof(pair_batch);
    for (int k = 0; k < d->n_meshes; k++) {
        const mesh_wall *m = &d->meshes[k];
        b += (size_t)m->nv * (m->x_binned ? 4 : 3) * 3 * sizeof(double); /* x_ref x x_build (x_binned) */
        b += (size_t)m->nt * (6 * sizeof(int32_t) + 3 * sizeof(double)) + (size_t)m->ne * sizeof(int32_t);
        const size_t cells = m->bin_start ? (size_t)m->bin_ncell[0] * m->bin_ncell[1] * m->bin_ncell[2] + 1 : 0;
        b += (cells + (size_t)m->bin_capacity) * sizeof(int32_t);
    }
    return b;
}
