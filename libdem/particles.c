/* Particles: validated bulk insertion (all-or-nothing, overlap-checked), removal,
 * read-back in ascending id order. */
#include "internal.h"
#include "cell_grid.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

static int reserve_particles(dem_domain *d, int64_t need)
{
    if (need <= d->cap) return 1;
    /* a bulk insertion gets exactly its size (doubling would leave up to half of ~200 B per
     * particle unused); repeated small ones grow by half, amortised */
    int64_t c = d->cap + d->cap / 2;
    if (c < need) c = need;
    if (c < 1024) c = 1024;
    void **vec3[] = {(void **)&d->x, (void **)&d->v, (void **)&d->w, (void **)&d->f, (void **)&d->t, (void **)&d->x_build};
    void **scalar[] = {(void **)&d->radius, (void **)&d->inv_mass, (void **)&d->inv_inertia};
    void **i32[] = {(void **)&d->mat, (void **)&d->cell_of, (void **)&d->perm, (void **)&d->trans_lo,
                    (void **)&d->trans_hi, (void **)&d->deferred};
    void **i64[] = {(void **)&d->id, (void **)&d->trans_start};
    void **u8[] = {(void **)&d->is_direct};
    if (!dem_realloc_all(vec3, 6, (size_t)c * 3, sizeof(double)) || !dem_realloc_all(scalar, 3, (size_t)c, sizeof(double)) ||
        !dem_realloc_all(i32, 6, (size_t)c, sizeof(int32_t)) || !dem_realloc_all(i64, 2, (size_t)c + 1, sizeof(int64_t)) ||
        !dem_realloc_all(u8, 1, (size_t)c, 1))
        return 0;
    d->cap = c;
    return 1;
}

static int reserve_ids(dem_domain *d, int64_t need)
{
    if (need <= d->cap_ids) return 1;
    int64_t c = d->cap_ids > 0 ? d->cap_ids : 1024;
    while (c < need) c *= 2;
    int32_t *p = dem_realloc_array(d->index_of_id, (size_t)c, sizeof *p);
    if (!p) return 0;
    d->index_of_id = p;
    d->cap_ids = c;
    return 1;
}

int dem_particles_reserve(dem_domain *d, int64_t n, int64_t next_id)
{
    return reserve_particles(d, n) && reserve_ids(d, next_id);
}

/* Index of the first particle (existing or new) that overlaps another one by more than
 * insert_overlap_ratio of the smaller radius; fills *other. Uses a temporary cell grid. */
static int64_t find_overlap(dem_domain *d, int64_t n_new, const double *pos, const double *rad, int64_t *other,
                            int *no_memory)
{
    const int64_t n_old = d->n, total = n_old + n_new;
    double rmax = d->r_max;
    for (int64_t k = 0; k < n_new; k++)
        if (rad[k] > rmax) rmax = rad[k];
    cell_grid g;
    for (int a = 0; a < 3; a++) {
        double len = d->def.hi[a] - d->def.lo[a];
        g.n[a] = (int)floor(len / (2.0 * rmax));
        if (g.n[a] < 1) g.n[a] = 1;
        if (g.n[a] > 1024) g.n[a] = 1024;
    }
    while ((int64_t)g.n[0] * g.n[1] * g.n[2] > 2 * total + 1024) {
        int a = g.n[0] >= g.n[1] && g.n[0] >= g.n[2] ? 0 : (g.n[1] >= g.n[2] ? 1 : 2);
        g.n[a] = (g.n[a] + 1) / 2;
    }
    for (int a = 0; a < 3; a++) {
        g.lo[a] = d->def.lo[a];
        g.size[a] = (d->def.hi[a] - d->def.lo[a]) / g.n[a];
    }
    const int *nc = g.n;
    int32_t *cellc = dem_malloc((size_t)total * 3 * sizeof *cellc);
    if (!cellc || !cell_grid_alloc(&g, total)) {
        dem_free(cellc);
        *no_memory = 1;
        return -1;
    }
#define P(q) ((q) < n_old ? d->x + 3 * (q) : pos + 3 * ((q) - n_old))
#define R(q) ((q) < n_old ? d->radius[(q)] : rad[(q) - n_old])
    for (int64_t q = 0; q < total; q++) {
        const double *p = P(q);
        for (int a = 0; a < 3; a++) {
            double u = p[a] - d->def.lo[a];
            if (d->def.periodic[a]) {
                double len = d->def.hi[a] - d->def.lo[a];
                u -= floor(u / len) * len;
            }
            cellc[3 * q + a] = cell_clamp(floor(u / g.size[a]), nc[a]);
        }
        cell_grid_push(&g, q, cell_index(nc, cellc[3 * q], cellc[3 * q + 1], cellc[3 * q + 2]));
    }
    int64_t found = -1;
    for (int64_t q = n_old; q < total && found < 0; q++) {
        const double *p = P(q);
        for (int dz = -1; dz <= 1 && found < 0; dz++)
            for (int dy = -1; dy <= 1 && found < 0; dy++)
                for (int dx = -1; dx <= 1 && found < 0; dx++) {
                    int c3[3] = {cellc[3 * q] + dx, cellc[3 * q + 1] + dy, cellc[3 * q + 2] + dz}, skip = 0;
                    int off[3] = {dx, dy, dz};
                    for (int a = 0; a < 3; a++) {
                        if (c3[a] < 0 || c3[a] >= nc[a]) {
                            if (!d->def.periodic[a]) skip = 1;
                            c3[a] = (c3[a] + nc[a]) % nc[a];
                        }
                        /* with fewer than 3 cells an axis would revisit a cell */
                        if (d->def.periodic[a] && nc[a] < 3 && off[a] != 0 && (nc[a] == 1 || off[a] < 0)) skip = 1;
                    }
                    if (skip) continue;
                    for (int64_t o = g.head[cell_index(nc, c3[0], c3[1], c3[2])]; o >= 0; o = g.next[o]) {
                        if (o == q || (o >= n_old && o > q)) continue; /* each new pair once */
                        const double *po = P(o);
                        double r2 = 0.0;
                        for (int a = 0; a < 3; a++) {
                            double u = p[a] - po[a];
                            if (d->def.periodic[a]) {
                                double len = d->def.hi[a] - d->def.lo[a];
                                u -= len * floor(u / len + 0.5);
                            }
                            r2 += u * u;
                        }
                        double ro = R(o), rq = R(q);
                        double lim = ro + rq - d->def.insert_overlap_ratio * (ro < rq ? ro : rq);
                        if (r2 < lim * lim) {
                            found = q;
                            *other = o;
                            break;
                        }
                    }
                }
    }
#undef P
#undef R
    cell_grid_free(&g);
    dem_free(cellc);
    return found;
}

dem_status dem_particles_add(dem_domain *d, int64_t n, const double *pos, const double *rad, const dem_material *material,
                             const double *vel, const double *angvel, dem_particle_id *ids)
{
    if (!d) return DEM_ERR_NULL;
    if (n < 0) return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_particles_add: count must be >= 0, got %lld", (long long)n);
    if (n == 0) {
        dem_clear_error(d);
        return DEM_OK;
    }
    if (!pos || !rad || !material)
        return dem_fail(d, DEM_ERR_NULL, "dem_particles_add: position, radius and material must not be NULL");
    if (n > INT32_MAX - d->n)
        return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_particles_add: at most %d particles per domain", INT32_MAX);
    for (int64_t k = 0; k < n; k++) {
        for (int a = 0; a < 3; a++) {
            if (!dem_is_finite(pos[3 * k + a]))
                return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_particles_add: particle %lld: position is not finite",
                                (long long)k);
            if (vel && !dem_is_finite(vel[3 * k + a]))
                return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_particles_add: particle %lld: velocity is not finite",
                                (long long)k);
            if (angvel && !dem_is_finite(angvel[3 * k + a]))
                return dem_fail(d, DEM_ERR_INVALID_ARGUMENT,
                                "dem_particles_add: particle %lld: angular velocity is not finite", (long long)k);
            if (!d->def.periodic[a] && (pos[3 * k + a] < d->def.lo[a] || pos[3 * k + a] > d->def.hi[a]))
                return dem_fail(d, DEM_ERR_OUT_OF_BOUNDS,
                                "dem_particles_add: particle %lld: position %g on axis %d is outside [%g, %g]",
                                (long long)k, pos[3 * k + a], a, d->def.lo[a], d->def.hi[a]);
        }
        if (!dem_is_finite(rad[k]) || rad[k] <= 0.0)
            return dem_fail(d, DEM_ERR_INVALID_ARGUMENT,
                            "dem_particles_add: particle %lld: radius must be finite and > 0 m, got %g", (long long)k,
                            rad[k]);
        if (material[k].index < 0 || material[k].index >= d->n_materials)
            return dem_fail(d, DEM_ERR_UNKNOWN_MATERIAL,
                            "dem_particles_add: particle %lld: unknown material %d (%d materials exist)", (long long)k,
                            (int)material[k].index, d->n_materials);
        for (int w = 0; w < d->n_walls; w++) {
            const plane_wall *pw = &d->walls[w];
            double dist = (pos[3 * k + pw->def.axis] - pw->def.position) * pw->def.side;
            if (dist < rad[k] * (1.0 - d->def.insert_overlap_ratio))
                return dem_fail(d, DEM_ERR_OVERLAP, "dem_particles_add: particle %lld overlaps plane wall %d", (long long)k,
                                w);
        }
    }
    int cut_mesh = -1;
    int64_t cut = dem_meshes_cut_particles(d, n, pos, rad, &cut_mesh);
    if (cut >= 0)
        return dem_fail(d, DEM_ERR_OVERLAP, "dem_particles_add: particle %lld overlaps mesh wall %d", (long long)cut,
                        cut_mesh);
    int no_memory = 0;
    int64_t other = -1;
    int64_t bad = find_overlap(d, n, pos, rad, &other, &no_memory);
    if (no_memory) return dem_fail(d, DEM_ERR_NO_MEMORY, "dem_particles_add: out of memory");
    if (bad >= 0) {
        if (other < d->n)
            return dem_fail(d, DEM_ERR_OVERLAP, "dem_particles_add: particle %lld overlaps existing particle id %lld",
                            (long long)(bad - d->n), (long long)d->id[other]);
        return dem_fail(d, DEM_ERR_OVERLAP, "dem_particles_add: particles %lld and %lld overlap",
                        (long long)(other - d->n), (long long)(bad - d->n));
    }
    if (!reserve_particles(d, d->n + n) || !reserve_ids(d, d->next_id + n))
        return dem_fail(d, DEM_ERR_NO_MEMORY, "dem_particles_add: out of memory for %lld particles", (long long)(d->n + n));
    for (int64_t k = 0; k < n; k++) {
        int64_t i = d->n + k;
        const dem_material_def *m = &d->materials[material[k].index];
        double r = rad[k];
        double mass = m->density * 4.0 / 3.0 * DEM_PI * r * r * r;
        for (int a = 0; a < 3; a++) {
            d->x[3 * i + a] = pos[3 * k + a];
            d->v[3 * i + a] = vel ? vel[3 * k + a] : 0.0;
            d->w[3 * i + a] = angvel ? angvel[3 * k + a] : 0.0;
            d->f[3 * i + a] = d->t[3 * i + a] = 0.0;
        }
        d->radius[i] = r;
        d->inv_mass[i] = 1.0 / mass;
        d->inv_inertia[i] = 1.0 / (0.4 * mass * r * r);
        d->mat[i] = material[k].index;
        d->id[i] = d->next_id;
        d->index_of_id[d->next_id] = (int32_t)i;
        if (ids) ids[k] = d->next_id;
        d->next_id++;
        if (r > d->r_max) d->r_max = r;
    }
    d->n += n;
    d->need_rebuild = 1;
    d->forces_valid = 0;
    d->rayleigh_cache = -1.0;
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_particles_remove(dem_domain *d, int64_t n, const dem_particle_id *ids)
{
    if (!d) return DEM_ERR_NULL;
    if (n < 0) return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "dem_particles_remove: count must be >= 0");
    if (n == 0) return DEM_OK;
    if (!ids) return dem_fail(d, DEM_ERR_NULL, "dem_particles_remove: ids must not be NULL");
    unsigned char *mask = dem_calloc((size_t)d->n + 1, 1);
    if (!mask) return dem_fail(d, DEM_ERR_NO_MEMORY, "dem_particles_remove: out of memory");
    for (int64_t k = 0; k < n; k++) {
        dem_particle_id id = ids[k];
        int32_t i = (id >= 0 && id < d->next_id) ? d->index_of_id[id] : -1;
        if (i < 0 || mask[i]) {
            dem_free(mask);
            return dem_fail(d, DEM_ERR_UNKNOWN_PARTICLE, "dem_particles_remove: id %lld is not a live particle%s",
                            (long long)id, i >= 0 ? " (listed twice)" : "");
        }
        mask[i] = 1;
    }
    dem_status s = dem_neighbor_rebuild(d, mask);
    dem_free(mask);
    if (s != DEM_OK) return s;
    d->forces_valid = 0;
    d->rayleigh_cache = -1.0;
    dem_clear_error(d);
    return DEM_OK;
}

int64_t dem_particle_count(const dem_domain *d) { return d ? d->n : 0; }

/* Copy `width` doubles per particle from src into out, ascending id order. */
static dem_status read_back(const dem_domain *d, const double *src, int width, double *out, int64_t capacity,
                            const char *fn)
{
    if (!d || !out) return DEM_ERR_NULL;
    dem_status s = dem_check_room(d, capacity, d->n, "particles", fn);
    if (s != DEM_OK) return s;
    int64_t q = 0;
    for (dem_particle_id id = 0; id < d->next_id; id++) {
        int32_t i = d->index_of_id[id];
        if (i < 0) continue;
        memcpy(out + width * q, src + (int64_t)width * i, (size_t)width * sizeof(double));
        q++;
    }
    return DEM_OK;
}

dem_status dem_particles_get_ids(const dem_domain *d, dem_particle_id *ids, int64_t capacity)
{
    if (!d || !ids) return DEM_ERR_NULL;
    dem_status s = dem_check_room(d, capacity, d->n, "particles", "dem_particles_get_ids");
    if (s != DEM_OK) return s;
    int64_t q = 0;
    for (dem_particle_id id = 0; id < d->next_id; id++)
        if (d->index_of_id[id] >= 0) ids[q++] = id;
    return DEM_OK;
}

#define GETTER(name, field, width)                                                        \
    dem_status dem_particles_get_##name(const dem_domain *d, double *p, int64_t capacity) \
    {                                                                                     \
        return read_back(d, d ? d->field : NULL, width, p, capacity, "dem_particles_get_" #name); \
    }
GETTER(positions, x, 3)
GETTER(velocities, v, 3)
GETTER(angular_velocities, w, 3)
GETTER(forces, f, 3)
GETTER(torques, t, 3)
GETTER(radii, radius, 1)
#undef GETTER

static dem_status write_vec3(dem_domain *d, double *dst, const double *src, const char *fn)
{
    if (!d) return DEM_ERR_NULL;
    if (!src) return dem_fail(d, DEM_ERR_NULL, "%s: array must not be NULL", fn);
    int64_t q = 0;
    for (int64_t k = 0; k < 3 * d->n; k++)
        if (!dem_is_finite(src[k]))
            return dem_fail(d, DEM_ERR_INVALID_ARGUMENT, "%s: entry %lld is not finite", fn, (long long)k);
    for (dem_particle_id id = 0; id < d->next_id; id++) {
        int32_t i = d->index_of_id[id];
        if (i < 0) continue;
        memcpy(dst + 3 * (int64_t)i, src + 3 * q, 3 * sizeof(double));
        q++;
    }
    d->forces_valid = 0;
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_particles_set_velocities(dem_domain *d, const double *v)
{
    return write_vec3(d, d ? d->v : NULL, v, "dem_particles_set_velocities");
}

dem_status dem_particles_set_angular_velocities(dem_domain *d, const double *w)
{
    return write_vec3(d, d ? d->w : NULL, w, "dem_particles_set_angular_velocities");
}
